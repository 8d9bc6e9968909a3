// The Cu benchmark of the staggered scheme (issue 17, "Speed"): a packing.csv (SI metres) sintered
// at T for t_end with strategy 1 or 2; prints the run time and its split. Not a test.
//   bench_staggered PACKING.csv [--strategy 1|2] [--time T_END] [--dt-max S] [--temperature T]
//                   [--new-contacts 0|1] [--eps-lim E] [--material cu|ti] [--E PA]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "netdem/packing/io.hpp"
#include "netdem/quasistatic/staggered.hpp"

int main(int argc, char** argv) {
  namespace cs = netdem::contact::sinter;
  namespace st = netdem::qs::staggered;
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_staggered PACKING.csv [--strategy S] [--time T] [--dt-max S] [--temperature T] "
                         "[--new-contacts 0|1] [--eps-lim E]\n");
    return 2;
  }
  st::StaggeredOptions o;
  double t_end = 5000.0, T = 1293.0;
  std::string material = "cu";
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const double v = std::atof(argv[i + 1]);
    if (k == "--material") {
      material = argv[i + 1];
      continue;
    }
    if (k == "--strategy") o.strategy = static_cast<int>(v);
    else if (k == "--time") t_end = v;
    else if (k == "--dt-max") o.dt_max = v;
    else if (k == "--temperature") T = v;
    else if (k == "--new-contacts") o.new_contacts = v != 0.0;
    else if (k == "--eps-lim") o.eps_lim = v;
    else if (k == "--E") o.E = v;
    else {
      std::fprintf(stderr, "bench_staggered: unknown option %s\n", k.c_str());
      return 2;
    }
  }
  const auto pk = netdem::packing::read_packing_csv(argv[1]);
  const auto p = st::Particles::from_packing(pk);
  const auto t0 = std::chrono::steady_clock::now();
  st::Staggered s(p, cs::builtin_sinter_material(material), cs::TemperatureProfile::constant(T), o);
  const std::size_t c0 = s.contacts().size();
  long substeps = 0, refactor = 0, gmres = 0, rejected = 0;
  while (s.time() < t_end) {
    const auto r = s.step(t_end);
    substeps += r.substeps;
    refactor += r.refactorised;
    gmres += r.gmres_iterations;
    rejected += r.rejected;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto& tm = s.timers();
  const Eigen::Matrix3d F = s.homogeneous_strain();
  double neck = 0.0;
  int frozen = 0;
  for (const auto& c : s.contacts()) {
    neck += c.pair.x_over_R();
    frozen += c.frozen;
  }
  neck /= static_cast<double>(s.contacts().size());
  std::printf("particles %zu contacts %zu -> %zu (frozen %d) steps %ld rejected %ld substeps %ld refactorisations %ld "
              "gmres %ld\n",
              p.size(), c0, s.contacts().size(), frozen, s.steps(), rejected, substeps, refactor, gmres);
  std::printf("shrink %.9e %.9e %.9e density %.7f neck %.9f\n", -F(0, 0), -F(1, 1), -F(2, 2), s.density(), neck);
  std::printf("wall %.3f s: detect %.3f integrate %.3f assemble %.3f factorise %.3f solve %.3f correct %.3f\n", wall,
              tm.detect, tm.integrate, tm.assemble, tm.factorise, tm.solve, tm.correct);
  return 0;
}
