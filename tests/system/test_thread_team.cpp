// sys::ThreadTeam (thread_team.hpp): every member runs once per run, the barrier orders the members'
// writes, an exception of any member reaches the caller (the lowest member's), and the team stays
// usable after it; TeamHandle's copies start without a team.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/system/thread_team.hpp"

using netdem::sys::TeamHandle;
using netdem::sys::ThreadTeam;

TEST(ThreadTeam, EveryMemberOncePerRun) {
  for (int n : {1, 2, 3, 5}) {
    ThreadTeam team(n);
    std::vector<int> hits(static_cast<std::size_t>(n), 0);
    int seen_n = 0;
    auto f = [&](int t, int nt) {
      ++hits[static_cast<std::size_t>(t)];
      if (t == 0) seen_n = nt;
    };
    for (int r = 0; r < 200; ++r) team.run(f);
    EXPECT_EQ(seen_n, n);
    for (int h : hits) EXPECT_EQ(h, 200) << n << " members";
  }
}

// Each member writes its slot, passes the barrier and reads every slot: it must see all the writes
// of this round (a barrier that let a member through early would read a previous round's value).
TEST(ThreadTeam, BarrierOrdersTheWrites) {
  const int n = 3;
  ThreadTeam team(n);
  std::vector<int> slot(n, -1);
  std::atomic<int> bad{0};
  for (int round = 0; round < 300; ++round) {
    auto f = [&](int t, int nt) {
      slot[static_cast<std::size_t>(t)] = round;
      team.barrier();
      for (int u = 0; u < nt; ++u)
        if (slot[static_cast<std::size_t>(u)] != round) ++bad;
      team.barrier();  // (nobody writes the next round's value before all have read)
    };
    team.run(f);
  }
  EXPECT_EQ(bad.load(), 0);
}

TEST(ThreadTeam, ExceptionsReachTheCaller) {
  ThreadTeam team(3);
  auto f = [](int t, int) {
    if (t >= 1) throw std::runtime_error("member " + std::to_string(t));
  };
  try {
    team.run(f);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "member 1");  // the lowest member's
  }
  int sum = 0;
  std::atomic<int> count{0};
  auto g = [&](int, int) { ++count; };
  team.run(g);  // still usable
  sum = count.load();
  EXPECT_EQ(sum, 3);
  EXPECT_THROW(ThreadTeam(0), std::invalid_argument);
}

TEST(ThreadTeam, HandleCopiesStartEmpty) {
  TeamHandle a;
  ThreadTeam& t2 = a.get(2);
  EXPECT_EQ(t2.size(), 2);
  EXPECT_EQ(&a.get(2), &t2);  // kept while the size is the same
  TeamHandle b(a);
  EXPECT_NE(&b.get(2), &t2);  // a copy makes its own
  EXPECT_EQ(a.get(3).size(), 3);
}
