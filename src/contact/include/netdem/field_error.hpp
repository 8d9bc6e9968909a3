#pragma once
// A bad value of a named input field, thrown by the libraries (which know no command line): the
// message names the quantity ("the compression strain rate must be ..."), field() names the
// field of the options structure ("strain_rate"). A command line whose option is the field's name
// with '-' for '_' (--strain-rate) reports it under that option (apps/common/run_status.hpp).
#include <stdexcept>
#include <string>
#include <utility>

namespace netdem {

class FieldError : public std::invalid_argument {
 public:
  FieldError(std::string field, const std::string& what) : std::invalid_argument(what), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

}  // namespace netdem
