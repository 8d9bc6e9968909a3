#pragma once
// netsolve yield's records and files (yield_records.cpp): the analytic affine surface of a run,
// one probe's files (probes/probe_NNN.csv and .json) and its record, yield_points.csv assembled
// from the records, and yield-merge. The run itself: yield.cpp.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/yield_driver.hpp"

namespace netdem::app::netsolve::yield {

/// A result value for JSON: null where it is not finite (no NaN in a result file).
nlohmann::json jnum(double v);
/// A JSON number, or NaN for null.
double from_json(const nlohmann::json& j);

/// The analytic affine surface of the run (docs/yield_analytic.md).
struct Analytic {
  bool ok = false;
  netdem::qs::AffineYieldInput in{};
  std::string message;
};

/// The analytic surface of the run's setup["analytic"]; not ok (with the message) if it has none.
Analytic make_analytic(const nlohmann::json& a);

/// "hydrostatic precompaction to D = ..., friction ..., die-die": the title of a run's setup.
std::string setup_title(const nlohmann::json& setup);

/// The files and record of a finished probe (probes/probe_NNN.csv and .json); a probe that failed
/// with an error gets the record of failed_record (and only its .json).
nlohmann::json write_probe(const netdem::qs::ProbeResult& p, int directions, const Analytic& an, const nlohmann::json& setup,
                           const std::filesystem::path& out);

/// The record of probe `index` that has no result: every point null, status and end `why`.
nlohmann::json failed_record(int index, int directions, const std::string& why, const Analytic& an, const nlohmann::json& setup);

/// yield_points.csv of the records (in this order) in `out` (apps/scripts/plot_yield.py plots it).
void write_yield_points(const std::filesystem::path& out, const std::vector<nlohmann::json>& recs);

/// netsolve yield-merge: the probe records of several run folders assembled in `out_dir`.
int run_merge(const std::vector<std::string>& dirs, const std::string& out_dir, const std::string& command, bool overwrite);

}  // namespace netdem::app::netsolve::yield
