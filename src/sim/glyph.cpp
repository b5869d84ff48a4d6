#include "hattr/sim/glyph.hpp"

#include "hattr/core/text_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/sim/data_dir.hpp"

namespace hattr::sim {
namespace {

using nlohmann::json;

constexpr std::array kGlyphTopKeys{"format", "version", "name", "character", "unicode", "description", "units",
                              "size_note", "shape_note", "source_note", "strokes"};
constexpr std::array kStrokeKeys{"note", "points"};

void checkKeys(const json& object, const auto& keys, std::string_view where) {
  for (const auto& item : object.items()) {
    const bool known = std::any_of(keys.begin(), keys.end(), [&](const char* k) { return item.key() == k; });
    HATTR_THROW_UNLESS(known, "{}: unknown key \"{}\": expected one of {}", where, item.key(), fmt::join(keys, ", "));
  }
}

std::string optionalText(const json& object, const char* key, std::string_view where) {
  const auto it = object.find(key);
  if (it == object.end()) return {};
  HATTR_THROW_UNLESS(it->is_string(), "{}: key {}: expected a string, got {}", where, key, jsonExcerpt(*it));
  return it->get<std::string>();
}

bool isUnicodeLabel(const std::string& text) {
  if (text.size() < 6 || text.size() > 8 || text.compare(0, 2, "U+") != 0) return false;
  return std::all_of(text.begin() + 2, text.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; });
}

}  // namespace

Glyph parseGlyph(std::string_view json_text, std::string_view source) {
  const json root = parseJsonObject(json_text, source);
  checkKeys(root, kGlyphTopKeys, source);

  const auto format = root.find("format");
  HATTR_THROW_UNLESS(format != root.end() && format->is_string() && *format == "hattr-glyph",
                     "{}: key format: expected \"hattr-glyph\", got {}", source,
                     format == root.end() ? std::string("nothing") : jsonExcerpt(*format));
  const auto version = root.find("version");
  HATTR_THROW_UNLESS(version != root.end() && version->is_number_integer() && *version == 1,
                     "{}: key version: expected 1, got {}", source,
                     version == root.end() ? std::string("nothing") : jsonExcerpt(*version));

  Glyph glyph;
  glyph.name = optionalText(root, "name", source);
  HATTR_THROW_UNLESS(!glyph.name.empty(), "{}: key name: expected a non-empty string, got {}", source,
                     root.contains("name") ? jsonExcerpt(root["name"]) : std::string("nothing"));
  glyph.unicode = optionalText(root, "unicode", source);
  HATTR_THROW_UNLESS(glyph.unicode.empty() || isUnicodeLabel(glyph.unicode),
                     "{}: key unicode: expected \"U+\" and 4 to 6 hex digits (or \"\"), got \"{}\"", source, glyph.unicode);
  glyph.character = optionalText(root, "character", source);
  for (const char* key : {"description", "units", "size_note", "shape_note", "source_note"}) {
    (void)optionalText(root, key, source);
  }

  const auto strokes = root.find("strokes");
  HATTR_THROW_UNLESS(strokes != root.end() && strokes->is_array() && !strokes->empty(),
                     "{}: key strokes: expected a non-empty list of strokes, got {}", source,
                     strokes == root.end() ? std::string("nothing") : jsonExcerpt(*strokes));
  for (std::size_t s = 0; s < strokes->size(); ++s) {
    const json& stroke = (*strokes)[s];
    const std::string where = fmt::format("{}: stroke {}", source, s + 1);
    HATTR_THROW_UNLESS(stroke.is_object(), "{}: expected an object with \"points\", got {}", where, jsonExcerpt(stroke));
    checkKeys(stroke, kStrokeKeys, where);
    GlyphStroke out;
    out.note = optionalText(stroke, "note", where);
    const auto points = stroke.find("points");
    HATTR_THROW_UNLESS(points != stroke.end() && points->is_array() && points->size() >= 2,
                       "{}: key points: expected a list of at least two [x_mm, y_mm] points, got {}", where,
                       points == stroke.end() ? std::string("nothing") : jsonExcerpt(*points));
    for (std::size_t p = 0; p < points->size(); ++p) {
      const json& point = (*points)[p];
      const bool numbers = point.is_array() && point.size() == 2 && point[0].is_number() && point[1].is_number();
      const bool finite = numbers && std::isfinite(point[0].get<double>()) && std::isfinite(point[1].get<double>());
      const bool inside = finite && std::abs(point[0].get<double>()) <= kMaxGlyphCoordinate_mm &&
                          std::abs(point[1].get<double>()) <= kMaxGlyphCoordinate_mm;
      HATTR_THROW_UNLESS(inside, "{}, point {}: expected [x_mm, y_mm], two finite numbers within ±{} mm, got {}", where,
                         p + 1, kMaxGlyphCoordinate_mm, jsonExcerpt(point));
      const Vec2 position(units::millimetresToMetres(point[0].get<double>()),
                          units::millimetresToMetres(point[1].get<double>()));
      HATTR_THROW_UNLESS(out.points.empty() || position != out.points.back(),
                         "{}, point {}: expected a point different from point {}, got the same {}", where, p + 1, p,
                         jsonExcerpt(point));
      out.points.push_back(position);
    }
    glyph.strokes.push_back(std::move(out));
  }
  return glyph;
}

Glyph loadGlyph(const std::filesystem::path& file) { return parseGlyph(readTextFile(file), file.string()); }

std::vector<Glyph> builtInGlyphs() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(defaultDataDir() / "glyphs")) {
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<Glyph> glyphs;
  for (const auto& file : files) glyphs.push_back(loadGlyph(file));
  return glyphs;
}

// A path first (what is clearly one, or a file that is there), then a built-in name, then a
// built-in character.
namespace {

// The files a built-in glyph of that name or character would be in: data/glyphs/NAME.json, and a
// letter's or digit's small-x, capital-x or digit-x (the letter library's names).
std::vector<std::filesystem::path> likelyFiles(std::string_view name) {
  std::vector<std::filesystem::path> files;
  const std::filesystem::path folder = defaultDataDir() / "glyphs";
  if (name.find('/') == std::string_view::npos) files.push_back(folder / (std::string(name) + ".json"));
  if (name.size() == 1 && std::isalnum(static_cast<unsigned char>(name[0])) != 0) {
    const unsigned char c = static_cast<unsigned char>(name[0]);
    const std::string stem = std::islower(c) != 0   ? fmt::format("small-{}", name)
                             : std::isupper(c) != 0 ? fmt::format("capital-{}", static_cast<char>(std::tolower(c)))
                                                    : fmt::format("digit-{}", name);
    files.push_back(folder / (stem + ".json"));
  }
  return files;
}

// The built-in glyph with that name or character: its likely file first (one file read), else
// every built-in glyph (another glyph file in the folder may use any file name).
std::optional<Glyph> lookUpBuiltInGlyph(std::string_view name) {
  const auto matches = [name](const Glyph& g) { return g.name == name || (!g.character.empty() && g.character == name); };
  std::error_code ec;
  for (const auto& file : likelyFiles(name)) {
    if (!std::filesystem::is_regular_file(file, ec)) continue;
    Glyph glyph = loadGlyph(file);
    if (matches(glyph)) return glyph;
  }
  for (Glyph& glyph : builtInGlyphs()) {
    if (matches(glyph)) return std::move(glyph);
  }
  return std::nullopt;
}

[[noreturn]] void throwUnknownGlyph(std::string_view name) {
  // The letter library by its characters alone; the other glyphs by name (and character).
  std::vector<std::string> known;
  std::string characters;
  for (const Glyph& g : builtInGlyphs()) {
    if (g.character.size() == 1 && std::isalnum(static_cast<unsigned char>(g.character[0])) != 0) {
      characters += g.character;
    } else {
      known.push_back(g.character.empty() ? g.name : fmt::format("{} ({})", g.name, g.character));
    }
  }
  if (!characters.empty()) known.push_back(fmt::format("a letter or digit by its character ({})", characters));
  throw InputError(fmt::format("glyph \"{}\": no such file, and no built-in glyph has that name or character; "
                               "expected a glyph file or one of: {} (hattr sim glyphs lists them)",
                               name, fmt::join(known, ", ")));
}

}  // namespace

Glyph findGlyph(std::string_view name) {
  HATTR_THROW_UNLESS(!name.empty(), "glyph: expected a file, a built-in glyph's name or a character, got \"\"");
  const std::filesystem::path as_path(name);
  // A path or a .json name is a file; otherwise a built-in glyph's name or character comes
  // first (a file "a" in the working folder does not hide the letter a), then an existing file.
  if (name.find('/') != std::string_view::npos || as_path.extension() == ".json") return loadGlyph(as_path);
  if (auto glyph = lookUpBuiltInGlyph(name)) return std::move(*glyph);
  std::error_code ec;
  if (std::filesystem::is_regular_file(as_path, ec)) return loadGlyph(as_path);
  throwUnknownGlyph(name);
}

Glyph findBuiltInGlyph(std::string_view name) {
  if (auto glyph = lookUpBuiltInGlyph(name)) return std::move(*glyph);
  throwUnknownGlyph(name);
}

double glyphPathLength(const Glyph& glyph) {
  double length = 0.0;
  for (const auto& stroke : glyph.strokes) {
    for (std::size_t i = 1; i < stroke.points.size(); ++i) length += (stroke.points[i] - stroke.points[i - 1]).norm();
  }
  return length;
}

GlyphBounds glyphBounds(const Glyph& glyph) {
  GlyphBounds box{.min = Vec2::Constant(std::numeric_limits<double>::infinity()),
                  .max = Vec2::Constant(-std::numeric_limits<double>::infinity())};
  for (const auto& stroke : glyph.strokes) {
    for (const Vec2& p : stroke.points) {
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
    }
  }
  return box;
}

}  // namespace hattr::sim
