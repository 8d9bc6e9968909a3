// Packing CSV files: format in io.hpp and docs/packing.md.
#include "netdem/packing/io.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace netdem::packing {

namespace {

std::string_view trim(std::string_view s) {
  const auto ws = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; };
  while (!s.empty() && ws(s.front())) s.remove_prefix(1);
  while (!s.empty() && ws(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t b = 0;
  for (;;) {
    const std::size_t e = s.find(sep, b);
    out.push_back(trim(s.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b)));
    if (e == std::string_view::npos) return out;
    b = e + 1;
  }
}

std::vector<std::string_view> split_ws(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

bool parse_double(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && ptr == s.data() + s.size();
}

template <class Int>
bool parse_int(std::string_view s, Int& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && ptr == s.data() + s.size();
}

/// Position of the first control character (bytes < 0x20 except tab, and 0x7f), or npos.
std::size_t control_char(std::string_view s) {
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if ((c < 0x20 && c != '\t') || c == 0x7f) return i;
  }
  return std::string_view::npos;
}

/// First word of a comment: the reserved keywords "box" and "seed" are interpreted, not kept.
std::string_view keyword(std::string_view comment) {
  const auto w = split_ws(comment);
  return w.empty() ? std::string_view{} : w.front();
}

}  // namespace

std::string quote_input(std::string_view s, std::size_t max_chars) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    out += c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
  }
  if (s.size() > max_chars) out += "...";
  return out;
}

void write_packing_csv(const Packing& p, const std::filesystem::path& path) {
  validate(p);
  for (const std::string& c : p.comments) {
    if (c.find_first_of("\r\n") != std::string::npos)
      throw std::invalid_argument("write_packing_csv: a comment contains a line break");
    if (control_char(c) != std::string_view::npos)
      throw std::invalid_argument("write_packing_csv: a comment contains a control character");
    const std::string_view k = keyword(c);
    if (k == "box" || k == "seed" || k == "dim" || k == "periodic" || k == "cell")
      throw std::invalid_argument(fmt::format("write_packing_csv: comment '{}' starts with a reserved word", quote_input(c)));
  }
  std::string text;
  text.reserve(64 * p.size() + 256);
  if (p.dim == 3) {  // 3D: six-number box and a dim line (docs/packing.md)
    text += fmt::format("# box {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n# dim 3\n", p.box.x_min, p.box.y_min,
                        p.box.z_min, p.box.x_max, p.box.y_max, p.box.z_max);
  } else {
    text += fmt::format("# box {:.17g} {:.17g} {:.17g} {:.17g}\n", p.box.x_min, p.box.y_min, p.box.x_max, p.box.y_max);
  }
  if (p.seed != 0) text += fmt::format("# seed {}\n", p.seed);
  if (p.periodic) {  // issue 29: the cell (the box's edges unless a '# cell' line gives its vectors)
    text += "# periodic\n";
    if (!p.cell.empty()) {
      text += "# cell";
      for (double v : p.cell) text += fmt::format(" {:.17g}", v);
      text += "\n";
    }
  }
  for (const std::string& c : p.comments) text += "# " + std::string(trim(c)) + "\n";
  if (p.dim == 3) {
    text += "id,x,y,z,r\n";
    for (std::size_t i = 0; i < p.size(); ++i)
      text += fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g}\n", i, p.x[i], p.y[i], p.z[i], p.r[i]);
  } else {
    text += "id,x,y,r\n";
    for (std::size_t i = 0; i < p.size(); ++i) text += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", i, p.x[i], p.y[i], p.r[i]);
  }

  // Atomic replace: write a sibling temporary file, flush, then rename over the target.
  const std::filesystem::path tmp =
      path.parent_path() / fmt::format(".{}.tmp.{}", path.filename().string(), static_cast<long>(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("write_packing_csv: cannot create '{}'", tmp.string()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(fmt::format("write_packing_csv: write to '{}' failed", tmp.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignore;
    std::filesystem::remove(tmp, ignore);
    throw std::runtime_error(fmt::format("write_packing_csv: cannot rename to '{}': {}", path.string(), ec.message()));
  }
}

namespace {

/// The packing-file reader's state, one method per kind of line (docs/packing.md "File format").
class CsvParser {
 public:
  explicit CsvParser(const std::string& file) : file_(file) {}

  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw std::runtime_error(fmt::format("{}:{}: {}", file_, line, what));
  }
  // one field against its documented range (docs/packing.md, "Valid ranges")
  void coordinate(std::size_t line, const char* what, double v) const {
    if (!(std::fabs(v) <= kMaxCoordinate))
      fail(line, fmt::format("{} = {} is outside [-{:g}, {:g}] (file units; docs/packing.md)", what, v, kMaxCoordinate,
                             kMaxCoordinate));
  }

  void read(std::istream& in) {
    std::string raw;
    while (std::getline(in, raw)) {
      ++ln_;
      const std::string_view line = trim(raw);
      if (line.empty()) continue;
      if (const std::size_t c = control_char(line); c != std::string_view::npos)
        fail(ln_, fmt::format("control character (byte {}) in column {}: not a text packing file",
                              static_cast<int>(static_cast<unsigned char>(line[c])), c + 1));
      if (line.front() == '#')
        comment_line(trim(line.substr(1)));
      else if (!have_header_)
        header_line(line);
      else
        data_line(line);
    }
    if (in.bad()) throw std::runtime_error(fmt::format("{}: read error after line {}", file_, ln_));
  }

  /// The whole-file checks, the ids sorted, validate(); the packing in id order.
  Packing finish();

 private:
  void comment_line(std::string_view body) {
    const std::string_view k = keyword(body);
    if (k == "box") {
      box_line(body);
    } else if (k == "dim") {
      const auto w = split_ws(body);
      if (w.size() != 2 || (w[1] != "2" && w[1] != "3")) fail(ln_, "dim line must be '# dim 2' or '# dim 3'");
      if (have_dim_) fail(ln_, fmt::format("second dim line (first on line {})", dim_line_));
      if (have_header_)
        fail(ln_, fmt::format("dim line after the header (line {}): '# dim 3' must come before the header", header_line_));
      p_.dim = w[1] == "3" ? 3 : 2;
      have_dim_ = true;
      dim_line_ = ln_;
    } else if (k == "periodic") {
      if (split_ws(body).size() != 1) fail(ln_, "periodic line must be '# periodic'");
      if (p_.periodic) fail(ln_, "second periodic line");
      p_.periodic = true;
    } else if (k == "cell") {
      cell_line(body);
    } else if (k == "seed") {
      const auto w = split_ws(body);
      if (w.size() != 2 || !parse_int(w[1], p_.seed)) fail(ln_, "seed line must be '# seed <unsigned integer>'");
      if (have_seed_) fail(ln_, "second seed line");
      have_seed_ = true;
    } else {
      p_.comments.emplace_back(body);
    }
  }

  void box_line(std::string_view body) {
    const auto w = split_ws(body);
    double v[6];
    if (w.size() != 5 && w.size() != 7)
      fail(ln_, "box line must be '# box x_min y_min x_max y_max' (2D) or '# box x_min y_min z_min x_max y_max z_max' (3D)");
    const int nv = static_cast<int>(w.size()) - 1;
    for (int i = 0; i < nv; ++i)
      if (!parse_double(w[static_cast<std::size_t>(i) + 1], v[i]))
        fail(ln_, fmt::format("box line: non-numeric field '{}'", quote_input(w[static_cast<std::size_t>(i) + 1])));
    for (int i = 0; i < nv; ++i)
      if (!std::isfinite(v[i])) fail(ln_, "box line: NaN or infinite bound");
    if (have_box_) fail(ln_, fmt::format("second box line (first on line {})", box_line_));
    if (nv == 4) {
      if (!(v[2] > v[0]) || !(v[3] > v[1])) fail(ln_, "box line: box has non-positive size");
      static constexpr const char* kBound[4] = {"box x_min", "box y_min", "box x_max", "box y_max"};
      for (int i = 0; i < 4; ++i) coordinate(ln_, kBound[i], v[i]);
      if (!(v[2] - v[0] >= kMinBoxSize) || !(v[3] - v[1] >= kMinBoxSize))
        fail(ln_, fmt::format("box line: width {} or height {} is below {:g} (file units; docs/packing.md)",
                              v[2] - v[0], v[3] - v[1], kMinBoxSize));
      p_.box = {v[0], v[1], v[2], v[3]};
    } else {
      if (!(v[3] > v[0]) || !(v[4] > v[1]) || !(v[5] > v[2])) fail(ln_, "box line: box has non-positive size");
      static constexpr const char* kBound[6] = {"box x_min", "box y_min", "box z_min", "box x_max", "box y_max", "box z_max"};
      for (int i = 0; i < 6; ++i) coordinate(ln_, kBound[i], v[i]);
      if (!(v[3] - v[0] >= kMinBoxSize) || !(v[4] - v[1] >= kMinBoxSize) || !(v[5] - v[2] >= kMinBoxSize))
        fail(ln_, fmt::format("box line: size {} x {} x {} is below {:g} along some axis (file units; docs/packing.md)",
                              v[3] - v[0], v[4] - v[1], v[5] - v[2], kMinBoxSize));
      p_.box = {v[0], v[1], v[3], v[4], v[2], v[5]};
    }
    box_dim_ = nv == 6 ? 3 : 2;
    have_box_ = true;
    box_line_ = ln_;
  }

  void cell_line(std::string_view body) {
    const auto w = split_ws(body);
    if (w.size() != 5 && w.size() != 10)
      fail(ln_, "cell line must be '# cell a1x a1y a2x a2y' (2D) or '# cell' with the 9 components of a1 a2 a3 (3D)");
    if (cell_line_ != 0) fail(ln_, fmt::format("second cell line (first on line {})", cell_line_));
    p_.cell.clear();
    for (std::size_t i = 1; i < w.size(); ++i) {
      double v = 0;
      if (!parse_double(w[i], v)) fail(ln_, fmt::format("cell line: non-numeric field '{}'", quote_input(w[i])));
      if (!std::isfinite(v)) fail(ln_, "cell line: NaN or infinite component");
      coordinate(ln_, "cell component", v);
      p_.cell.push_back(v);
    }
    cell_line_ = ln_;
  }

  void header_line(std::string_view line) {
    const auto f = split(line, ',');
    const bool three = p_.dim == 3;
    const bool h2 = f.size() == 4 && f[0] == "id" && f[1] == "x" && f[2] == "y" && f[3] == "r";
    const bool h3 = f.size() == 5 && f[0] == "id" && f[1] == "x" && f[2] == "y" && f[3] == "z" && f[4] == "r";
    if (three && h2) fail(ln_, fmt::format("header 'id,x,y,r' is 2D, but line {} says '# dim 3' (expected 'id,x,y,z,r')", dim_line_));
    if (!three && h3)
      fail(ln_, "header 'id,x,y,z,r' is 3D, but there is no '# dim 3' line before it (a 3D file needs '# dim 3')");
    if (three ? !h3 : !h2)
      fail(ln_, fmt::format("bad header '{}', expected '{}'", quote_input(line), three ? "id,x,y,z,r" : "id,x,y,r"));
    have_header_ = true;
    header_line_ = ln_;
  }

  void data_line(std::string_view line) {
    const auto f = split(line, ',');
    const bool three = p_.dim == 3;
    const std::size_t nf = three ? 5 : 4;
    if (f.size() != nf) fail(ln_, fmt::format("expected {} fields ({}), got {}", nf, three ? "id,x,y,z,r" : "id,x,y,r", f.size()));
    long long id = 0;
    if (!parse_int(f[0], id) || id < 0) fail(ln_, fmt::format("id '{}' is not a non-negative integer", quote_input(f[0])));
    double v[4];
    static constexpr const char* kName2[3] = {"x", "y", "r"};
    static constexpr const char* kName3[4] = {"x", "y", "z", "r"};
    const char* const* kName = three ? kName3 : kName2;
    const std::size_t nv = nf - 1;
    for (std::size_t i = 0; i < nv; ++i) {
      if (!parse_double(f[i + 1], v[i])) fail(ln_, fmt::format("non-numeric {} '{}'", kName[i], quote_input(f[i + 1])));
      if (!std::isfinite(v[i])) fail(ln_, fmt::format("{} is {} (disk id {})", kName[i], quote_input(f[i + 1]), id));
    }
    const double rad = v[nv - 1];
    if (!(rad > 0)) fail(ln_, fmt::format("r <= 0 (r = {}, disk id {})", rad, id));
    if (!(rad >= kMinRadius && rad <= kMaxRadius))
      fail(ln_, fmt::format("r = {} (disk id {}) is outside [{:g}, {:g}] (file units; docs/packing.md)", rad, id,
                            kMinRadius, kMaxRadius));
    coordinate(ln_, "x", v[0]);
    coordinate(ln_, "y", v[1]);
    if (three) coordinate(ln_, "z", v[2]);
    if (ids_.size() >= kMaxDisks) fail(ln_, fmt::format("more than {} disks", kMaxDisks));
    ids_.push_back(id);
    lines_.push_back(ln_);
    p_.x.push_back(v[0]);
    p_.y.push_back(v[1]);
    if (three) p_.z.push_back(v[2]);
    p_.r.push_back(rad);
  }

  void check_structure() const;
  void check_ranges(const std::vector<std::size_t>& order) const;

  std::string file_;
  Packing p_;
  bool have_box_ = false, have_seed_ = false, have_header_ = false, have_dim_ = false;
  std::size_t box_line_ = 0, dim_line_ = 0, header_line_ = 0, cell_line_ = 0;
  int box_dim_ = 2;  // 4 numbers: 2D box, 6 numbers: 3D box
  std::vector<long long> ids_;
  std::vector<std::size_t> lines_;  // source line of each disk
  std::size_t ln_ = 0;
};

// The lines that must be there, and every centre in the box.
void CsvParser::check_structure() const {
  const Packing& p = p_;
  if (!have_box_)
    fail(ln_, p.dim == 3 ? "missing '# box x_min y_min z_min x_max y_max z_max' line" : "missing '# box x_min y_min x_max y_max' line");
  if (box_dim_ != p.dim)
    fail(box_line_, p.dim == 3 ? fmt::format("box line has 4 numbers (a 2D box), but line {} says '# dim 3' (expected "
                                             "'# box x_min y_min z_min x_max y_max z_max')",
                                             dim_line_)
                               : "box line has 6 numbers (a 3D box), but there is no '# dim 3' line (a 2D box is "
                                 "'# box x_min y_min x_max y_max')");
  if (!have_header_) fail(ln_, p.dim == 3 ? "missing header 'id,x,y,z,r'" : "missing header 'id,x,y,r'");
  if (cell_line_ != 0 && !p.periodic) fail(cell_line_, "a cell line needs a '# periodic' line");
  if (cell_line_ != 0 && p.cell.size() != static_cast<std::size_t>(p.dim * p.dim))
    fail(cell_line_, fmt::format("cell line has {} numbers, a {}D cell {}", p.cell.size(), p.dim, p.dim * p.dim));
  if (p.size() == 0) fail(ln_, "no disks");

  for (std::size_t i = 0; i < p.size(); ++i) {  // same criterion as validate(): centre in the box
    const double t = 1e-9 * p.r[i];
    const Box& b = p.box;
    if (p.x[i] < b.x_min - t || p.x[i] > b.x_max + t || p.y[i] < b.y_min - t || p.y[i] > b.y_max + t)
      fail(lines_[i], p.dim == 3 ? fmt::format("sphere id {} is outside the box (centre ({}, {}, {}))", ids_[i], p.x[i], p.y[i], p.z[i])
                                 : fmt::format("disk id {} is outside the box (centre ({}, {}))", ids_[i], p.x[i], p.y[i]));
    if (p.dim == 3 && (p.z[i] < b.z_min - t || p.z[i] > b.z_max + t))
      fail(lines_[i], fmt::format("sphere id {} is outside the box (centre ({}, {}, {}))", ids_[i], p.x[i], p.y[i], p.z[i]));
  }
}

// Duplicate ids (given the id order), the radius ratio and pairs too close.
void CsvParser::check_ranges(const std::vector<std::size_t>& order) const {
  const Packing& p = p_;
  for (std::size_t k = 1; k < order.size(); ++k)
    if (ids_[order[k]] == ids_[order[k - 1]])
      fail(lines_[order[k]], fmt::format("duplicate id {} (first on line {})", ids_[order[k]], lines_[order[k - 1]]));
  // radius ratio: name the lines of the smallest and the largest disk
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    if (p.r[i] < p.r[lo]) lo = i;
    if (p.r[i] > p.r[hi]) hi = i;
  }
  if (!(p.r[hi] <= kMaxRadiusRatio * p.r[lo]))
    fail(lines_[hi], fmt::format("r_max / r_min = {:.6g} / {:.6g} = {:.6g} exceeds {:g} (r_min on line {})", p.r[hi],
                                 p.r[lo], p.r[hi] / p.r[lo], kMaxRadiusRatio, lines_[lo]));
  // pairs too close (cell grid): name both lines; exact duplicates keep validate()'s wording
  if (const auto c = find_close_pair(p)) {
    if (c->duplicate) {  // numbered by id rank, as validate() numbers them
      auto rank = [&](std::size_t i) {
        return static_cast<std::size_t>(std::find(order.begin(), order.end(), i) - order.begin());
      };
      const std::size_t a = rank(c->i), b = rank(c->j);
      throw std::runtime_error(fmt::format("{}: invalid packing: disk {} duplicates disk {} (same centre; lines {} and {})",
                                           file_, std::max(a, b), std::min(a, b), lines_[order[std::max(a, b)]],
                                           lines_[order[std::min(a, b)]]));
    }
    fail(lines_[c->i], fmt::format("disk id {} and disk id {} (line {}) are too close: centre distance {:.6g} < max(r_i, "
                                   "r_j) = {:.6g}",
                                   ids_[c->i], ids_[c->j], lines_[c->j], c->distance, std::max(p.r[c->i], p.r[c->j])));
  }
}

Packing CsvParser::finish() {
  check_structure();
  // Sort by id (ids in any order), reject duplicates.
  std::vector<std::size_t> order(p_.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return ids_[a] < ids_[b]; });
  check_ranges(order);
  Packing q;
  q.box = p_.box;
  q.dim = p_.dim;
  q.seed = p_.seed;
  q.comments = std::move(p_.comments);
  q.periodic = p_.periodic;
  q.cell = p_.cell;
  q.x.reserve(p_.size());
  q.y.reserve(p_.size());
  q.r.reserve(p_.size());
  if (p_.dim == 3) q.z.reserve(p_.size());
  for (std::size_t i : order) {
    q.x.push_back(p_.x[i]);
    q.y.push_back(p_.y[i]);
    if (p_.dim == 3) q.z.push_back(p_.z[i]);
    q.r.push_back(p_.r[i]);
  }
  try {
    validate(q);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: {}", file_, e.what()));
  }
  return q;
}

}  // namespace

Packing read_packing_csv(std::istream& in, const std::string& file) {
  CsvParser parser(file);
  parser.read(in);
  return parser.finish();
}

Packing read_packing_csv(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::runtime_error(fmt::format("{}: is a directory, not a packing file", file));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open file", file));
  return read_packing_csv(in, file);
}

}  // namespace netdem::packing
