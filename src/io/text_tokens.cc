#include "io/text_tokens.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "io/io_internal.h"

namespace femreg {
namespace internal {

bool ParseInt(const std::string& text, long long* value) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size()) return false;
  *value = v;
  return true;
}

bool ParseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return false;
  *value = v;
  return true;
}

std::string Quoted(const std::string& text, size_t max_chars) {
  // Control bytes and bytes outside ASCII (a binary file read as text) as \xNN, so that a
  // message does not write raw binary to the user's terminal.
  std::ostringstream os;
  os << "'";
  const size_t n = std::min(text.size(), max_chars);
  for (size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      os << text[i];
    } else {
      static const char kHex[] = "0123456789abcdef";
      os << "\\x" << kHex[c >> 4] << kHex[c & 15];
    }
  }
  os << (text.size() > max_chars ? "...'" : "'");
  if (text.size() > max_chars) os << " (" << text.size() << " bytes)";
  return os.str();
}

long long MaxItemsIn(size_t bytes, long long tokens_each) {
  if (tokens_each <= 0) tokens_each = 1;
  // n items need n * tokens_each tokens and n * tokens_each - 1 separators at least.
  return static_cast<long long>((bytes + 1) / 2) / tokens_each;
}

Status TokenStream::CheckCount(const char* what, long long count, long long tokens_each) const {
  std::ostringstream os;
  if (count < 0) {
    os << what << " is negative (" << count << ")";
    return Error(os.str());
  }
  const long long most = MaxItemsIn(remaining(), tokens_each);
  if (count > most) {
    os << what << " is " << count << ", more than the rest of the file can hold (" << remaining()
       << " bytes, at most " << most << ")";
    return Error(os.str());
  }
  return Status::Ok();
}

Status TokenStream::Open(const std::string& path, char comment) {
  path_ = path;
  comment_ = comment;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Status::Error(path + ": read error");
  data_ = ss.str();
  pos_ = 0;
  current_line_ = 1;
  last_line_ = 1;
  return Status::Ok();
}

std::vector<std::string> TokenStream::TakeLines(int n) {
  std::vector<std::string> lines;
  for (int i = 0; i < n && pos_ < data_.size(); ++i) {
    const size_t end = data_.find('\n', pos_);
    const size_t stop = end == std::string::npos ? data_.size() : end;
    std::string line = data_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
    last_line_ = current_line_;
    pos_ = end == std::string::npos ? data_.size() : end + 1;
    if (end != std::string::npos) ++current_line_;
  }
  return lines;
}

void TokenStream::SkipSpace() {
  while (pos_ < data_.size()) {
    const char c = data_[pos_];
    if (c == '\n') {
      ++current_line_;
      ++pos_;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
    } else {
      break;
    }
  }
}

bool TokenStream::Next(Token* token) {
  SkipSpace();
  if (pos_ >= data_.size()) return false;  // errors then name the last line with a token
  const size_t start = pos_;
  while (pos_ < data_.size()) {
    const char c = data_[pos_];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') break;
    if (comment_ != '\0' && c == comment_) break;
    ++pos_;
  }
  token->text.assign(data_, start, pos_ - start);
  token->line = current_line_;
  last_line_ = current_line_;
  return true;
}

bool TokenStream::Peek(Token* token) {
  const size_t pos = pos_;
  const int current = current_line_, last = last_line_;
  const bool ok = Next(token);
  pos_ = pos;
  current_line_ = current;
  last_line_ = last;
  return ok;
}

std::vector<Token> TokenStream::RestOfLine() {
  std::vector<Token> tokens;
  const int line = last_line_;
  Token t;
  while (Peek(&t) && t.line == line) {
    Next(&t);
    tokens.push_back(t);
  }
  last_line_ = line;
  return tokens;
}

Status TokenStream::NextInt(const char* what, long long* value) {
  Token t;
  if (!Next(&t)) return Error(std::string("unexpected end of file while reading ") + what);
  if (!ParseInt(t.text, value)) {
    return Error(std::string("expected ") + what + " (an integer), found " + Quoted(t.text));
  }
  return Status::Ok();
}

Status TokenStream::NextDouble(const char* what, double* value) {
  Token t;
  if (!Next(&t)) return Error(std::string("unexpected end of file while reading ") + what);
  if (!ParseDouble(t.text, value)) {
    return Error(std::string("expected ") + what + " (a number), found " + Quoted(t.text));
  }
  return Status::Ok();
}

Status TokenStream::NextWord(const char* what, std::string* value) {
  Token t;
  if (!Next(&t)) return Error(std::string("unexpected end of file while reading ") + what);
  *value = t.text;
  return Status::Ok();
}

Status TokenStream::TakeBytes(const char* what, size_t bytes, const char** data) {
  while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
  if (pos_ < data_.size()) ++pos_;
  binary_ = true;
  if (bytes > data_.size() - pos_) {
    std::ostringstream os;
    os << what << " needs " << bytes << " bytes, the file has " << data_.size() - pos_
       << " left (truncated file?)";
    return Error(os.str());
  }
  *data = data_.data() + pos_;
  pos_ += bytes;
  return Status::Ok();
}

Status TokenStream::Error(const std::string& message) const {
  if (binary_) {
    std::ostringstream os;
    os << "byte " << pos_ << ": " << message;
    return FileError(path_, 0, os.str());
  }
  return FileError(path_, last_line_, message);
}

Status TokenStream::ErrorAt(int line, const std::string& message) const {
  return FileError(path_, line, message);
}

}  // namespace internal
}  // namespace femreg
