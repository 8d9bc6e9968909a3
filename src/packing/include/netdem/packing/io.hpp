#pragma once
// Packing text files (CSV). Format (see docs/packing.md):
//
//   # box <x_min> <y_min> <x_max> <y_max>      required, once
//   # seed <S>                                   optional (unsigned 64-bit; absent -> seed 0)
//   # periodic                                   optional: periodic in every axis (issue 29)
//   # cell <a1x> <a1y> <a2x> <a2y>               optional, periodic only: the cell vectors (3D: 9
//                                                numbers); absent: the box's edges
//   # <free comment>                             optional, any number, kept in Packing::comments
//   id,x,y,r                                     header, exactly these four names
//   0,<x>,<y>,<r>                                one line per disk
//
// '#' lines may appear anywhere; blank lines are ignored; fields may be padded with spaces/tabs;
// CRLF line ends are accepted. Ids must be distinct non-negative integers in any order; disks are
// stored sorted by id and renumbered 0..N-1 (the writer writes the index as id). Numbers are
// written with %.17g, so write -> read reproduces every double exactly.
#include <cstddef>
#include <filesystem>
#include <istream>
#include <string>
#include <string_view>

#include "netdem/packing/packing.hpp"

namespace netdem::packing {

/// Writes `p` atomically: to a temporary file in the same directory, then renamed over `path`
/// (no half-written file is ever visible). Throws std::invalid_argument if validate(p) fails or a
/// comment cannot be stored (contains a line break, or starts with a reserved word: "box",
/// "seed", "dim", "periodic", "cell"); std::runtime_error on an I/O failure.
void write_packing_csv(const Packing& p, const std::filesystem::path& path);

/// At most `max_chars` printable ASCII characters of `s` for an error message: other bytes become
/// '?', a longer text is cut and marked "...". Every piece of input quoted in a reader's message
/// goes through it (issue 13: a binary first line was echoed whole, 5 MB of control characters).
std::string quote_input(std::string_view s, std::size_t max_chars = 80);

/// Valid ranges of the reader, in the file's length unit (docs/packing.md, "Valid ranges"): absurd
/// scales are refused at the door with a one-line error instead of reaching the solvers.
inline constexpr double kMaxCoordinate = 1e6;   ///< |box bound|, |x|, |y| <= 1e6
inline constexpr double kMinRadius = 1e-6;      ///< r >= 1e-6
inline constexpr double kMaxRadius = 1e6;       ///< r <= 1e6
inline constexpr double kMinBoxSize = 1e-6;     ///< box width and height >= 1e-6
inline constexpr std::size_t kMaxDisks = 10000000;  ///< at most 10^7 disks (~0.5 GB while reading)

/// Reads a packing file. Throws std::runtime_error with a one-line message "<file>:<line>: <what>"
/// for: missing/unreadable file, missing or malformed box line, malformed seed line, bad or
/// missing header, wrong field count, non-numeric field, NaN/inf value, r <= 0, bad or duplicate
/// id, disk outside the box; then runs validate() (its message is rethrown prefixed by the file).
/// Also (the valid ranges): a control character in a line (binary file), a radius, coordinate or
/// box outside the limits above, more than kMaxDisks disks, r_max / r_min > kMaxRadiusRatio (names
/// both lines), a pair closer than max(r_i, r_j) (find_close_pair(), names both lines), a
/// directory given as the file. Input quoted in a message is at most 80 printable characters.
Packing read_packing_csv(const std::filesystem::path& path);

/// The same reader on a stream (the file reader is a thin wrapper); `source` names the input in
/// the messages ("<source>:<line>: <what>").
Packing read_packing_csv(std::istream& in, const std::string& source);

}  // namespace netdem::packing
