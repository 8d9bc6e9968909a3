#include "output.hpp"

#include <cstdio>
#include <fstream>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

namespace netdem::app {

void write_file_atomic(const std::filesystem::path& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::random_device rd;
  const fs::path tmp = dir / fmt::format(".{}.tmp{:08x}", path.filename().string(), rd());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("cannot write '{}': cannot create a file in '{}'", path.string(), dir.string()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw std::runtime_error(fmt::format("cannot write '{}': write failed (disk full?)", path.string()));
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(fmt::format("cannot write '{}': {}", path.string(), ec.message()));
  }
}

void make_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error(fmt::format("cannot create output folder '{}': {}", dir.string(),
                                         ec ? ec.message() : "not a directory"));
}

void start_run_dir(const std::filesystem::path& dir) {
  make_output_dir(dir);
  std::error_code ec;
  std::filesystem::remove(dir / "summary.json", ec);
  if (ec) throw std::runtime_error(fmt::format("cannot remove the old '{}': {}", (dir / "summary.json").string(), ec.message()));
}

namespace {
void append_fields(std::string& s, const std::vector<Field>& fields) {
  for (const auto& f : fields) {
    s += fmt::format("        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">\n          ",
                     f.name, f.components);
    for (double v : f.values) s += fmt::format("{:.9g} ", v);
    s += "\n        </DataArray>\n";
  }
}
void append_points(std::string& s, const std::vector<double>& x, const std::vector<double>& y) {
  s += "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n          ";
  for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{:.12g} {:.12g} 0 ", x[p], y[p]);
  s += "\n        </DataArray>\n      </Points>\n";
}
}  // namespace

std::string vtp_particles(const std::vector<double>& x, const std::vector<double>& y, const std::vector<Field>& pd) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n";
  s += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
                   x.size(), x.size());
  append_points(s, x, y);
  s += "      <PointData>\n";
  append_fields(s, pd);
  s += "      </PointData>\n      <Verts>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ";
  for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{} ", p);
  s += "\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ";
  for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{} ", p + 1);
  s += "\n        </DataArray>\n      </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  return s;
}

std::string vtp_network(const std::vector<double>& x, const std::vector<double>& y, const std::vector<int>& i,
                        const std::vector<int>& j, const std::vector<Field>& cd) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n";
  s += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
                   x.size(), i.size());
  append_points(s, x, y);
  s += "      <CellData>\n";
  append_fields(s, cd);
  s += "      </CellData>\n      <Lines>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ";
  for (std::size_t k = 0; k < i.size(); ++k) s += fmt::format("{} {} ", i[k], j[k]);
  s += "\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ";
  for (std::size_t k = 0; k < i.size(); ++k) s += fmt::format("{} ", 2 * (k + 1));
  s += "\n        </DataArray>\n      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  return s;
}

Progress::Progress(std::string what, double total, bool quiet)
    : what_(std::move(what)), total_(total), quiet_(quiet), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(double done) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < 0.5) return;
  last_ = now;
  const double el = std::chrono::duration<double>(now - start_).count();
  const double frac = total_ > 0 ? done / total_ : 0.0;
  const double rate = el > 0 ? done / el : 0.0;
  const double eta = rate > 0 ? (total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r%s: %5.1f%%  %.1f/s  ETA %.0f s   ", what_.c_str(), 100.0 * frac, rate, eta);
  printed_ = true;
}

void Progress::finish() {
  if (quiet_) return;
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: done in %.2f s\n", printed_ ? "\r" : "", what_.c_str(), el);
}

}  // namespace netdem::app
