// Result<T>: a value or an error, for code that reports failures as codes
// (no exceptions inside the stack). The error carries an std::error_code
// (usually an SdoAbort, see sdo/abort.hpp) and a human-readable detail.
#pragma once

#include <string>
#include <system_error>
#include <utility>
#include <variant>

namespace canopen {

struct Error {
  std::error_code code;
  std::string detail;  // one line for an operator, e.g. "70000 is above 65535 (u16)"
};

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}          // NOLINT: implicit by design
  Result(Error error) : v_(std::move(error)) {}      // NOLINT
  Result(std::error_code code, std::string detail = {}) : v_(Error{code, std::move(detail)}) {}

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  // Precondition: ok().
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  // Precondition: !ok().
  const Error& error() const { return std::get<1>(v_); }
  std::error_code code() const { return ok() ? std::error_code{} : error().code; }

 private:
  std::variant<T, Error> v_;
};

}  // namespace canopen
