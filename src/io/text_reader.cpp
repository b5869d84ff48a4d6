#include <cerrno>
#include <charconv>
#include <cstring>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "text_reader_internal.hpp"

namespace hattr::io::detail {

bool LineReader::next(std::string& line) {
  if (!std::getline(in_, line)) return false;
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  // A UTF-8 byte-order mark (spreadsheets write one) is not part of the first line's text.
  constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
  if (line_number_ == 1 && line.starts_with(kUtf8Bom)) line.erase(0, kUtf8Bom.size());
  return true;
}

std::string LineReader::where() const { return fmt::format("{}:{}", source_, line_number_); }

std::ifstream openInputFile(const std::filesystem::path& file) {
  std::error_code ec;
  HATTR_THROW_UNLESS(!std::filesystem::is_directory(file, ec),
                     "{}: expected a file, got a directory", file.string());
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw InputError(fmt::format("{}: cannot open for reading: {}", file.string(),
                                 std::strerror(errno)));
  }
  return in;
}

std::vector<std::string_view> splitFields(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = line.find(separator, start);
    fields.push_back(line.substr(start, end == std::string_view::npos ? end : end - start));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return fields;
}

std::vector<std::string_view> splitBlanks(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

std::string_view trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

std::optional<double> parseDouble(std::string_view field) {
  field = trim(field);
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc{} || end != field.data() + field.size()) return std::nullopt;
  return value;
}

std::optional<long long> parseInteger(std::string_view field) {
  field = trim(field);
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return std::nullopt;
  long long value = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc{} || end != field.data() + field.size()) return std::nullopt;
  return value;
}

std::string quotedField(std::string_view field) {
  constexpr std::size_t kMax = 40;
  if (field.size() <= kMax) return fmt::format("\"{}\"", field);
  return fmt::format("\"{}...\"", field.substr(0, kMax));
}

}  // namespace hattr::io::detail
