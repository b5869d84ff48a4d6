#pragma once
// Line-oriented text parsing shared by the profile reader and the importers: line
// numbers for error messages, field splitting, strict number parsing.

#include <filesystem>
#include <fstream>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hattr::io::detail {

/// Reads lines, tracking the 1-based number of the last line read; strips a trailing '\r'.
class LineReader {
 public:
  LineReader(std::istream& in, std::string source) : in_(in), source_(std::move(source)) {}
  /// Reads the next line into `line`; false at the end of the input.
  bool next(std::string& line);
  [[nodiscard]] int lineNumber() const { return line_number_; }
  [[nodiscard]] const std::string& source() const { return source_; }
  /// "source:line", the prefix of every message about the last line read.
  [[nodiscard]] std::string where() const;

 private:
  std::istream& in_;
  std::string source_;
  int line_number_ = 0;
};

/// Opens a file for reading; throws InputError naming the file and the reason.
std::ifstream openInputFile(const std::filesystem::path& file);
/// Splits on `separator`, keeping empty fields.
std::vector<std::string_view> splitFields(std::string_view line, char separator);
/// Splits on runs of blanks (spaces, tabs).
std::vector<std::string_view> splitBlanks(std::string_view line);
std::string_view trim(std::string_view text);
/// The whole (trimmed) field as a double; nullopt if it is not one. "nan"/"inf" parse.
std::optional<double> parseDouble(std::string_view field);
/// The whole (trimmed) field as an integer; nullopt if it is not one.
std::optional<long long> parseInteger(std::string_view field);
/// A field quoted for an error message, shortened if long: "abc".
std::string quotedField(std::string_view field);

}  // namespace hattr::io::detail
