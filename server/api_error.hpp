// The error every request-path failure becomes: an HTTP status and a stable code for clients, with
// a message a user can act on. Rendered as {"error":{"code","message"}}.
#pragma once

#include <stdexcept>
#include <string>

namespace corridor::server {

class ApiError : public std::runtime_error {
 public:
  ApiError(int status, std::string code, const std::string& message)
      : std::runtime_error(message), status_(status), code_(std::move(code)) {}
  [[nodiscard]] int status() const { return status_; }
  [[nodiscard]] const std::string& code() const { return code_; }

 private:
  int status_;
  std::string code_;
};

inline ApiError bad_request(const std::string& message) { return {400, "bad_request", message}; }
inline ApiError not_found(const std::string& message) { return {404, "not_found", message}; }
inline ApiError conflict(const std::string& message) { return {409, "conflict", message}; }
inline ApiError unprocessable(const std::string& code, const std::string& message) { return {422, code, message}; }

}  // namespace corridor::server
