#include "hattr/io/table_csv.hpp"

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "text_reader_internal.hpp"

namespace hattr::io {

std::size_t Table::column(std::string_view name) const {
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i] == name) return i;
  }
  std::string names;
  for (const auto& c : columns) names += (names.empty() ? "" : ", ") + c;
  throw InputError(fmt::format("{}: no column \"{}\": expected one of {}", source, name, names));
}

std::vector<double> Table::numbers(std::string_view name) const {
  const std::size_t c = column(name);
  std::vector<double> out;
  out.reserve(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto v = detail::parseDouble(rows[r][c]);
    HATTR_THROW_UNLESS(v && std::isfinite(*v), "{}:{}: column {}: expected a finite number, got {}", source, r + 2, name,
                       detail::quotedField(rows[r][c]));
    out.push_back(*v);
  }
  return out;
}

std::vector<std::string> Table::text(std::string_view name) const {
  const std::size_t c = column(name);
  std::vector<std::string> out;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    HATTR_THROW_UNLESS(!rows[r][c].empty(), "{}:{}: column {}: expected a value, got an empty field", source, r + 2, name);
    out.push_back(rows[r][c]);
  }
  return out;
}

namespace {

/// Splits one CSV row (RFC 4180: fields may be quoted; "" inside quotes is a quote).
std::vector<std::string> splitRow(std::string_view line, const detail::LineReader& reader) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"' && std::string(detail::trim(fields.back())).empty()) {
      fields.back().clear();
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  HATTR_THROW_UNLESS(!quoted, "{}: a quoted field is not closed", reader.where());
  for (auto& f : fields) f = std::string(detail::trim(f));
  return fields;
}

}  // namespace

Table readTable(std::istream& in, std::string_view source) {
  detail::LineReader reader(in, std::string(source));
  Table table;
  table.source = source;
  std::string line;
  while (reader.next(line) && (line.empty() || line.front() == '#')) {
  }
  HATTR_THROW_UNLESS(!line.empty(), "{}: empty file: expected a header row of column names", source);
  table.columns = splitRow(line, reader);
  while (reader.next(line)) {
    if (line.empty()) continue;
    std::vector<std::string> row = splitRow(line, reader);
    HATTR_THROW_UNLESS(row.size() == table.columns.size(), "{}: expected {} fields, got {}", reader.where(),
                       table.columns.size(), row.size());
    table.rows.push_back(std::move(row));
  }
  HATTR_THROW_UNLESS(!table.rows.empty(), "{}: no data rows after the header", source);
  return table;
}

Table readTable(const std::filesystem::path& file) {
  std::ifstream in = detail::openInputFile(file);
  return readTable(in, file.string());
}

void writeTable(const Table& table, const std::filesystem::path& file, bool replace) {
  std::string text;
  const auto row = [&text](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      HATTR_THROW_UNLESS(cells[i].find_first_of(",\n\r") == std::string::npos,
                         "table cell {}: cannot contain a comma or a line break", detail::quotedField(cells[i]));
      text += (i ? "," : "") + cells[i];
    }
    text += '\n';
  };
  row(table.columns);
  for (const auto& r : table.rows) row(r);
  writeFileAtomically(file, text, replace ? Overwrite::kReplace : Overwrite::kRefuse);
}

std::string plainCell(std::string_view text) {
  std::string cell(text);
  for (char& c : cell) {
    if (c == ',') c = ';';
    if (c == '\n' || c == '\r') c = ' ';
  }
  return cell;
}

}  // namespace hattr::io
