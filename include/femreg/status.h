// femreg/status.h - a success flag with a message for user and data errors.
#ifndef FEMREG_STATUS_H_
#define FEMREG_STATUS_H_

#include <string>
#include <utility>

namespace femreg {

// User and data errors (a bad file, a bad scene, an empty cloud) come back as a
// Status whose message names the file, line or field. Programmer errors use
// assertions instead.
class Status {
 public:
  Status() = default;
  static Status Ok() { return Status(); }
  static Status Error(std::string message) { return Status(std::move(message)); }

  bool ok() const { return ok_; }
  const std::string& message() const { return message_; }
  explicit operator bool() const { return ok_; }

 private:
  explicit Status(std::string message) : ok_(false), message_(std::move(message)) {}
  bool ok_ = true;
  std::string message_;
};

}  // namespace femreg

#endif  // FEMREG_STATUS_H_
