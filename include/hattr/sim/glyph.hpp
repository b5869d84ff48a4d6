#pragma once
/// A skill to write, as data: a glyph is a list of strokes, each a list of via points in
/// writing order. Files are JSON in millimetres (data/glyphs/*.json, docs/simulation.md);
/// inside, metres in the paper plane of frame W (x to the writer's right, y away).
///
///   {"format": "hattr-glyph", "version": 1, "name": "na", "unicode": "U+0BA8",
///    "strokes": [{"note": "left leg", "points": [[-7.96, -3.09], [-7.96, 12.37]]}, ...]}
///
/// Descriptive fields (character, description, units, size_note, shape_note, source_note,
/// and each stroke's note) are optional strings; any other key is an error.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace hattr::sim {

/// A point in the paper plane [m].
using Vec2 = Eigen::Vector2d;

struct GlyphStroke {
  std::string note;           ///< what the stroke is ("left leg, upward")
  std::vector<Vec2> points;   ///< via points in writing order [m], at least two
};

struct Glyph {
  std::string name;           ///< the skill's name ("na")
  std::string unicode;        ///< "U+0BA8", or empty for a shape that is no character
  std::string character;      ///< the character itself, if any ("ந")
  std::vector<GlyphStroke> strokes;
};

/// The largest |x| or |y| a glyph point may have [mm]: the simulated pen's workspace is
/// 160 × 120 mm; a glyph must fit well inside it.
inline constexpr double kMaxGlyphCoordinate_mm = 50.0;

/// Parses a glyph file's text. `source_name` names the file in messages. Throws InputError
/// naming the file, the stroke and the point (counted from 1) for: invalid JSON, a wrong
/// format or version, a missing or empty name, a malformed unicode field, no strokes, a stroke
/// with fewer than two points, a point that is not two finite numbers within
/// ±kMaxGlyphCoordinate_mm, a point equal to the one before it, an unknown key.
Glyph parseGlyph(std::string_view json_text, std::string_view source_name);

/// Loads a glyph file (parseGlyph); throws InputError if it cannot be read.
Glyph loadGlyph(const std::filesystem::path& file);

/// A glyph as people name it: a file path (any name with a '/' or ending in .json), a built-in
/// glyph's name (data/glyphs/NAME.json: "na", "loop", "small-a") or the character itself ("ந",
/// "a", "A", "7"), or else an existing file of that name (a file "a" in the working folder does
/// not hide the letter a). Throws InputError naming what was tried and listing the built-in glyphs.
Glyph findGlyph(std::string_view name);
/// A built-in glyph by its name or character only (no file is looked for); InputError listing
/// the built-in glyphs otherwise.
Glyph findBuiltInGlyph(std::string_view name);

/// The built-in glyphs (data/glyphs/*.json), sorted by name.
std::vector<Glyph> builtInGlyphs();

/// Total pen-down path length of a glyph [m] (the sum of its strokes' polyline lengths).
double glyphPathLength(const Glyph& glyph);

/// The smallest axis-aligned box holding every via point of a glyph [m] (the written path may
/// bulge a little past it between via points). A glyph without points gives min = +inf, max = -inf.
struct GlyphBounds {
  Vec2 min;
  Vec2 max;
};
GlyphBounds glyphBounds(const Glyph& glyph);

}  // namespace hattr::sim
