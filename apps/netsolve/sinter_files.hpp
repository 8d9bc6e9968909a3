#pragma once
// netsolve sinter's files (sinter_files.cpp): laminar.csv, the .vtp snapshots and their .pvd,
// the options and material as JSON.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/staggered.hpp"

namespace netdem::app::netsolve {

std::string laminar_csv(const netdem::packing::Packing& pk, double lamina);
void write_snapshot(const std::filesystem::path& out, int k, const netdem::qs::staggered::Staggered& s);
std::string pvd(const std::vector<std::pair<int, double>>& snaps);
nlohmann::json options_json(const netdem::qs::staggered::StaggeredOptions& o);
nlohmann::json material_json(const netdem::contact::sinter::SinterMaterial& m, const std::string& source);

}  // namespace netdem::app::netsolve
