// The state archive: fields checked at the door (archive.hpp).
#include "netdem/system/archive.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "netdem/packing/io.hpp"

namespace netdem::sys {

namespace {
std::string where(const std::string& file, const std::string& pointer, const std::string& problem) {
  const std::string p = pointer.empty() ? "/" : pointer;
  return file.empty() ? p + ": " + problem : quote(file) + ": " + p + ": " + problem;
}
// RFC 6901: '~' -> "~0", '/' -> "~1"
std::string escape_key(std::string_view key) {
  std::string s;
  for (char c : key) {
    if (c == '~') s += "~0";
    else if (c == '/') s += "~1";
    else s += c;
  }
  return s;
}
const char* type_name(const Json& j) { return j.type_name(); }
// A value quoted for a message: its JSON text cut to 80 characters; an array or an object by its type and
// size (dump() recurses, and the whole of a large value is not needed to say it is the wrong type).
std::string shown(const Json& j) {
  if (j.is_structured()) return fmt::format("({} of {} elements)", j.type_name(), j.size());
  return quote(j.dump());
}
}  // namespace

FieldError::FieldError(std::string file, std::string pointer, std::string problem)
    : std::invalid_argument(where(file, pointer, problem)),
      file_(std::move(file)),
      pointer_(std::move(pointer)),
      problem_(std::move(problem)) {}

std::string quote(std::string_view s) { return packing::quote_input(s, 80); }

Json real_json(double v, std::string_view what) {
  if (std::isnan(v)) throw std::invalid_argument(fmt::format("{} is NaN: a state archive holds no NaN", what));
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}

Field::Field(const Json& j, std::string file, std::string pointer)
    : j_(&j), file_(std::move(file)), pointer_(std::move(pointer)) {}

void Field::fail(const std::string& problem) const { throw FieldError(file_, pointer_, problem); }

Field Field::operator[](std::string_view key) const {
  if (!j_->is_object()) fail(fmt::format("expected an object, found {}", type_name(*j_)));
  const auto it = j_->find(key);
  const std::string p = pointer_ + "/" + escape_key(key);
  if (it == j_->end()) throw FieldError(file_, p, "missing");
  return Field(*it, file_, p);
}

Field Field::operator[](std::size_t k) const { return Field((*j_)[k], file_, pointer_ + "/" + std::to_string(k)); }

bool Field::has(std::string_view key) const { return j_->is_object() && j_->find(key) != j_->end(); }

void Field::object(std::initializer_list<std::string_view> allowed) const {
  if (!j_->is_object()) fail(fmt::format("expected an object, found {}", type_name(*j_)));
  for (const auto& [key, value] : j_->items()) {
    bool known = false;
    for (auto a : allowed) known = known || a == key;
    if (!known) throw FieldError(file_, pointer_ + "/" + escape_key(key), "unknown member");
  }
}

void Field::array(std::size_t n) const {
  if (!j_->is_array()) fail(fmt::format("expected an array of {}, found {}", n, type_name(*j_)));
  if (j_->size() != n) fail(fmt::format("expected {} elements, found {}", n, j_->size()));
}

std::size_t Field::array(std::size_t lo, std::size_t hi) const {
  if (!j_->is_array()) fail(fmt::format("expected an array, found {}", type_name(*j_)));
  if (j_->size() < lo || j_->size() > hi) fail(fmt::format("expected {} to {} elements, found {}", lo, hi, j_->size()));
  return j_->size();
}

double Field::real() const {
  if (j_->is_string()) {
    const auto& s = j_->get_ref<const std::string&>();
    if (s == "inf" || s == "-inf") fail(fmt::format("must be a finite number, found \"{}\"", s));
  }
  if (!j_->is_number()) fail(fmt::format("expected a number, found {} {}", type_name(*j_), shown(*j_)));
  const double v = j_->get<double>();
  if (!std::isfinite(v)) fail(fmt::format("{} is not a finite double", shown(*j_)));
  return v;
}

double Field::real(double lo, double hi) const {
  const double v = real();
  if (hi == std::numeric_limits<double>::max() && !(v >= lo)) fail(fmt::format("{} is below {:g}", shown(*j_), lo));
  if (!(v >= lo && v <= hi)) fail(fmt::format("{} is outside [{:g}, {:g}]", shown(*j_), lo, hi));
  return v;
}

double Field::extended_real(double lo, double hi) const {
  double v = 0.0;
  if (j_->is_string()) {
    const auto& s = j_->get_ref<const std::string&>();
    if (s == "inf") v = std::numeric_limits<double>::infinity();
    else if (s == "-inf") v = -std::numeric_limits<double>::infinity();
    else fail(fmt::format("expected a number, \"inf\" or \"-inf\", found {}", shown(*j_)));
  } else {
    v = real();
  }
  if (!(v >= lo && v <= hi)) fail(fmt::format("{} is outside [{:g}, {:g}]", shown(*j_), lo, hi));
  return v;
}

std::int64_t Field::integer(std::int64_t lo, std::int64_t hi) const {
  if (!j_->is_number_integer()) fail(fmt::format("expected an integer, found {} {}", type_name(*j_), shown(*j_)));
  if (j_->is_number_unsigned() && j_->get<std::uint64_t>() > static_cast<std::uint64_t>(hi))
    fail(fmt::format("{} is outside [{}, {}]", shown(*j_), lo, hi));
  const auto v = j_->get<std::int64_t>();
  if (v < lo || v > hi) fail(fmt::format("{} is outside [{}, {}]", shown(*j_), lo, hi));
  return v;
}

bool Field::boolean() const {
  if (!j_->is_boolean()) fail(fmt::format("expected true or false, found {}", shown(*j_)));
  return j_->get<bool>();
}

std::string Field::string() const {
  if (!j_->is_string()) fail(fmt::format("expected a string, found {} {}", type_name(*j_), shown(*j_)));
  return j_->get<std::string>();
}

std::size_t Field::choice(std::initializer_list<std::string_view> choices) const {
  return choice(std::span<const std::string_view>(choices.begin(), choices.size()));
}

std::size_t Field::choice(std::span<const std::string_view> choices) const {
  const std::string s = string();
  std::size_t k = 0;
  std::string list;
  for (auto c : choices) {
    if (s == c) return k;
    list += (k++ ? ", " : "") + std::string(c);
  }
  fail(fmt::format("\"{}\" is not one of {}", quote(s), list));
}

Json parse_archive(std::string_view text, const std::string& file) {
  for (std::string_view old : {"# demsolve state", "netdem-network-state", "netdem-staggered-state"})
    if (text.substr(0, old.size()) == old)
      throw FieldError(file, "", "an old text state file (before issue 26): convert it with "
                                 "apps/scripts/convert_state.py OLD NEW");
  // the nesting depth, by the brackets outside strings, before parsing: nlohmann parses any depth, but a value
  // nested 1e5 deep overflowed the stack where it was dumped (a message, the record of origin; SIGSEGV found by
  // the campaign of issue 27). A state archive is at most 5 levels deep.
  std::size_t depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t at = 0; at < text.size(); ++at) {
    const char c = text[at];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxArchiveDepth)
        throw FieldError(file, "", fmt::format("not a state archive (nested more than {} levels deep at byte {})",
                                               kMaxArchiveDepth, at));
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  // a key twice in one object: nlohmann keeps the last silently, so two writers' values would mix
  std::vector<std::vector<std::string>> keys;  // the keys of each open object (a few each)
  std::string twice;
  const auto check_keys = [&](int, Json::parse_event_t ev, Json& parsed) {
    if (ev == Json::parse_event_t::object_start) {
      keys.emplace_back();
    } else if (ev == Json::parse_event_t::object_end) {
      keys.pop_back();
    } else if (ev == Json::parse_event_t::key && !keys.empty()) {
      const auto& k = parsed.get_ref<const std::string&>();
      auto& seen = keys.back();
      if (std::find(seen.begin(), seen.end(), k) != seen.end()) {
        if (twice.empty()) twice = k;
      } else {
        seen.push_back(k);
      }
    }
    return true;
  };
  Json j;
  try {
    j = Json::parse(text, check_keys);
  } catch (const Json::exception& e) {
    // nlohmann's parse_error carries the byte; out_of_range (a number beyond double) too, in its text
    const auto* pe = dynamic_cast<const Json::parse_error*>(&e);
    throw FieldError(file, "", pe ? fmt::format("not a JSON state archive (syntax error at byte {})", pe->byte)
                                  : "not a JSON state archive (a number out of range)");
  }
  if (!twice.empty())
    throw FieldError(file, "", fmt::format("not a state archive (the key \"{}\" appears twice in one object)", quote(twice)));
  return j;
}

int check_header(const Field& root, std::string_view kind, int max_version) {
  if (!root.json().is_object()) root.fail(fmt::format("not a state archive (a JSON {}, not an object)", root.json().type_name()));
  if (root["format"].string() != kArchiveFormat)
    root["format"].fail(fmt::format("expected \"{}\", found {}", kArchiveFormat, shown(root.json()["format"])));
  const std::string k = root["kind"].string();
  if (k != kind) root["kind"].fail(fmt::format("a {} state, expected a {} state", quote(k), kind));
  return static_cast<int>(root["version"].integer(1, max_version));
}

Json make_archive(std::string_view kind, int version) {
  Json j = Json::object();
  j["format"] = kArchiveFormat;
  j["kind"] = kind;
  j["version"] = version;
  return j;
}

std::string dump_archive(const Json& j) { return j.dump() + "\n"; }

std::string read_text_file(const std::string& path, std::string_view what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::invalid_argument(fmt::format("{} '{}' is a folder", what, quote(path)));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(fmt::format("cannot open {} '{}'", what, quote(path)));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text_file(const std::string& path, std::string_view text, std::string_view what) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error(fmt::format("cannot write the {} {}", what, tmp));
    f << text;
    f.flush();
    if (!f) throw std::runtime_error(fmt::format("cannot write the {} {}", what, tmp));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot rename {} to {}: {}", tmp, path, ec.message()));
}

}  // namespace netdem::sys
