#pragma once
/// A plain CSV table with a header row (for `hattr anova` and analysis exports): named
/// columns of text cells. Strict: every row has as many fields as the header; errors name
/// the file, the line and what was expected.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace hattr::io {

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  /// The index of a column; throws InputError naming the available ones.
  [[nodiscard]] std::size_t column(std::string_view name) const;
  /// A column as numbers; throws InputError naming the row and the value that is not one.
  [[nodiscard]] std::vector<double> numbers(std::string_view name) const;
  /// A column as text.
  [[nodiscard]] std::vector<std::string> text(std::string_view name) const;

  std::string source;  ///< for messages
};

Table readTable(const std::filesystem::path& file);
Table readTable(std::istream& in, std::string_view source_name);
/// Free text as a cell writeTable takes: each comma becomes a semicolon, each line break a space.
std::string plainCell(std::string_view text);
/// Writes a table atomically (refuses to replace an existing file unless `replace`).
void writeTable(const Table& table, const std::filesystem::path& file, bool replace = false);

}  // namespace hattr::io
