#pragma once
// The laws' Params and History in the state archive (archive.hpp): to_json / from_json in the
// laws' namespace, found by ADL (Field::get<T>(), nlohmann's json(v)). from_json checks every
// field (type, range: each Params also through its validate()) and throws sys::FieldError with
// the JSON pointer of the field. The laws themselves (netdem/contact) know nothing of it.
#include <span>
#include <string_view>

#include "netdem/contact/luding.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/system/archive.hpp"

namespace netdem::sys {
/// One LudingParams field by name (the archive's member names; the apps' --param NAME=VALUE).
struct LudingField {
  const char* name;
  double contact::LudingParams::*d;  ///< a number, or
  bool contact::LudingParams::*b;    ///< a switch
};
/// Every LudingParams field (Table 1, then the switches).
std::span<const LudingField> luding_fields();

/// The name of a law in the state archives (the DEM state's "law"), by the law's history type H
/// (of either dimension): one specialisation per law (its History's JSON: below).
template <class H>
struct LawName;
template <int D>
struct LawName<contact::LudingHistoryT<D>> {
  static constexpr std::string_view value = "luding";
};
template <int D>
struct LawName<contact::PlasticIndentationHistoryT<D>> {
  static constexpr std::string_view value = "plastic_indentation";
};
}  // namespace netdem::sys

namespace netdem::contact {

void to_json(sys::Json& j, const LudingParams& p);
void from_json(const sys::Json& j, LudingParams& p);
void to_json(sys::Json& j, const PlasticIndentationParams& p);
void from_json(const sys::Json& j, PlasticIndentationParams& p);

/// {"delta_max", "delta0", "k2_line", "k1_seen", "xi" (2D: a number; 3D: [x, y, z]), "fluid",
/// "sliding"}
void to_json(sys::Json& j, const LudingHistoryT<2>& h);
void from_json(const sys::Json& j, LudingHistoryT<2>& h);
void to_json(sys::Json& j, const LudingHistoryT<3>& h);
void from_json(const sys::Json& j, LudingHistoryT<3>& h);
/// {"u_max" (>= 0), "f_t" (2D: a number; 3D: [x, y, z]), "sliding"}
void to_json(sys::Json& j, const PlasticIndentationHistoryT<2>& h);
void from_json(const sys::Json& j, PlasticIndentationHistoryT<2>& h);
void to_json(sys::Json& j, const PlasticIndentationHistoryT<3>& h);
void from_json(const sys::Json& j, PlasticIndentationHistoryT<3>& h);

}  // namespace netdem::contact
