#pragma once
// Rattlers of a contact network (issue 28 item 4): the particles left out of the load-bearing
// backbone when every particle with fewer than `need` contacts is removed, recursively (removing
// one lowers its neighbours' counts), as in the jamming literature. Both solvers measure with it:
// the periodic packing route (dynamic/periodic_packing.cpp) and the network solver's history.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace netdem::sys {

/// The result of prune_rattlers: which particles are rattlers, their count, and the backbone's
/// contacts (both ends kept) and coordination 2 x contacts / particles kept.
struct Backbone {
  std::vector<std::uint8_t> rattler;  ///< 1 for a rattler
  std::size_t rattlers = 0;
  std::size_t contacts = 0;
  double Z = 0.0;
};

/// Prunes the n particles of the contacts (pi[k], pj[k]); wall[p] (empty or n entries) counts
/// contacts of p with fixed boundaries, which never leave. need: D + 1 (the count that can hold a
/// particle without friction), or D with friction.
inline Backbone prune_rattlers(std::size_t n, const std::vector<int>& pi, const std::vector<int>& pj,
                               const std::vector<int>& wall, int need) {
  Backbone b;
  std::vector<int> deg(n, 0);
  std::vector<std::vector<int>> adj(n);
  for (std::size_t k = 0; k < pi.size(); ++k) {
    ++deg[static_cast<std::size_t>(pi[k])];
    ++deg[static_cast<std::size_t>(pj[k])];
    adj[static_cast<std::size_t>(pi[k])].push_back(pj[k]);
    adj[static_cast<std::size_t>(pj[k])].push_back(pi[k]);
  }
  if (!wall.empty())
    for (std::size_t p = 0; p < n; ++p) deg[p] += wall[p];
  b.rattler.assign(n, 0);
  std::vector<int> stack;
  for (std::size_t p = 0; p < n; ++p)
    if (deg[p] < need) b.rattler[p] = 1, stack.push_back(static_cast<int>(p));
  while (!stack.empty()) {
    const int p = stack.back();
    stack.pop_back();
    for (int q : adj[static_cast<std::size_t>(p)])
      if (!b.rattler[static_cast<std::size_t>(q)] && --deg[static_cast<std::size_t>(q)] < need)
        b.rattler[static_cast<std::size_t>(q)] = 1, stack.push_back(q);
  }
  for (std::size_t p = 0; p < n; ++p) b.rattlers += b.rattler[p];
  for (std::size_t k = 0; k < pi.size(); ++k)
    b.contacts += !b.rattler[static_cast<std::size_t>(pi[k])] && !b.rattler[static_cast<std::size_t>(pj[k])];
  const std::size_t kept = n - b.rattlers;
  b.Z = kept > 0 ? 2.0 * static_cast<double>(b.contacts) / static_cast<double>(kept) : 0.0;
  return b;
}

}  // namespace netdem::sys
