// A whitespace tokenizer over a whole text file that remembers line numbers, for the
// readers of text mesh formats.
#ifndef FEMREG_IO_TEXT_TOKENS_H_
#define FEMREG_IO_TEXT_TOKENS_H_

#include <string>
#include <vector>

#include "femreg/status.h"

namespace femreg {
namespace internal {

struct Token {
  std::string text;
  int line = 0;
};

class TokenStream {
 public:
  // Reads the whole file. `comment` starts a comment up to the end of the line ('\0' for
  // none).
  Status Open(const std::string& path, char comment);

  // Skips the first `n` lines (headers read some other way) and returns them.
  std::vector<std::string> TakeLines(int n);

  // The next token, false at the end of the file.
  bool Next(Token* token);
  // Like Next but leaves the token in the stream.
  bool Peek(Token* token);
  // All remaining tokens on the line of the last token returned.
  std::vector<Token> RestOfLine();

  // Readers of one typed value; `what` names it in the error message.
  Status NextInt(const char* what, long long* value);
  Status NextDouble(const char* what, double* value);
  Status NextWord(const char* what, std::string* value);

  // "path:line: message" at the line of the last token (or the current line at the end).
  Status Error(const std::string& message) const;
  Status ErrorAt(int line, const std::string& message) const;

  // Binary data after a text header line (legacy VTK BINARY): skips the rest of the line
  // of the last token and its newline, then points *data at the next `bytes` bytes and
  // moves past them. Refuses, naming the byte offset, when the file is shorter. From then
  // on errors name byte offsets instead of lines (a line count is meaningless in binary).
  Status TakeBytes(const char* what, size_t bytes, const char** data);
  // The whole file, and the byte offset of the next unread character.
  const std::string& data() const { return data_; }
  size_t offset() const { return pos_; }

  // Refuses a header count before anything is sized from it: negative, or more items of
  // `tokens_each` whitespace-separated tokens than the rest of the file can hold (each
  // token takes at least one character and one separator). `what` names the count.
  Status CheckCount(const char* what, long long count, long long tokens_each) const;
  // Bytes not yet read.
  size_t remaining() const { return data_.size() - pos_; }

  const std::string& path() const { return path_; }
  int line() const { return last_line_; }

 private:
  void SkipSpace();
  std::string path_;
  std::string data_;
  size_t pos_ = 0;
  int current_line_ = 1;  // line of data_[pos_]
  int last_line_ = 1;     // line of the last token returned
  char comment_ = '\0';
  bool binary_ = false;  // errors name byte offsets
};

bool ParseInt(const std::string& text, long long* value);
bool ParseDouble(const std::string& text, double* value);

// `text` for an error message: whole when it has at most `max_chars` characters, else its
// first `max_chars` and "... (N bytes)", so that a bad 4 MB token is not echoed whole;
// bytes that are not printable ASCII as \xNN.
std::string Quoted(const std::string& text, size_t max_chars = 80);

// How many items of `tokens_each` tokens `bytes` characters of text can hold at most.
long long MaxItemsIn(size_t bytes, long long tokens_each);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_IO_TEXT_TOKENS_H_
