// Expected failures as values.
//
// A bad file, a bad key in a JSON file, a broken mesh: these are results, not crashes. Every
// message names what the user must fix ("light.json: key 'fov_y_deg': must lie in (0, 180), got
// 190"); the CLI prints it as "lightvol: <message>" and exits with its kind's code (cli/main.cpp:
// 1 for an unsound volume, 2 for the others). Broken internal invariants are not Results: they
// are LV_CHECKs (core/check.h) that stop loudly.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace lightvol {

// What kind of failure an Error is: what the caller may do about it.
enum class ErrorKind {
  bad_input,        // a file, key or parameter to fix (the default)
  unsound,          // a volume that fails its checks (check_volume, or a build refusing one)
  unrepresentable,  // a valid light whose volume float32 cannot hold (volume/float32_guard.h)
  io,               // the system refused a read or write (disk full, permissions, descriptors)
};

struct Error {
  std::string message;
  ErrorKind kind = ErrorKind::bad_input;
};

// Either a T or an Error. Accessing the wrong alternative is a broken invariant and aborts.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<0>(checked()); }
  const T& value() const& { return std::get<0>(const_cast<Result*>(this)->checked()); }
  T&& value() && { return std::get<0>(std::move(checked())); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const {
    if (ok()) {
      std::fprintf(stderr, "lightvol: internal error: error() on a successful Result\n");
      std::abort();
    }
    return std::get<1>(v_);
  }

 private:
  std::variant<T, Error>& checked() {
    if (!ok()) {
      std::fprintf(stderr, "lightvol: internal error: value() on a failed Result: %s\n",
                   std::get<1>(v_).message.c_str());
      std::abort();
    }
    return v_;
  }
  std::variant<T, Error> v_;
};

// Success or an Error, for operations with no value.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  static Status success() { return {}; }

  bool ok() const { return !error_.has_value(); }
  explicit operator bool() const { return ok(); }
  // Accessing the error of a success is a broken invariant and aborts, as Result::error() does.
  const Error& error() const {
    if (ok()) {
      std::fprintf(stderr, "lightvol: internal error: error() on a successful Status\n");
      std::abort();
    }
    return *error_;
  }

 private:
  std::optional<Error> error_;
};

}  // namespace lightvol
