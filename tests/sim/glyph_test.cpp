// Glyph files: the shipped skills load; bad files are rejected with the file, stroke and
// point named; the data directory is found through HATTR_DATA_DIR or the prefix the program is in
// (the build folder's staged share/hattr here).

#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/glyph.hpp"
#include "support/test_support.hpp"

namespace hattr::sim {
namespace {

using ::testing::HasSubstr;

/// A valid glyph file's text with `strokes` (JSON) in place of its strokes.
std::string glyphText(const std::string& strokes, const std::string& extra = "") {
  return R"({"format": "hattr-glyph", "version": 1, "name": "t", "unicode": "U+0BA8", )" + extra +
         R"("strokes": )" + strokes + "}";
}

/// The message of the InputError that parsing `text` throws ("" if none).
std::string glyphError(const std::string& text) {
  try {
    (void)parseGlyph(text, "bad.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// Sets an environment variable for one scope and restores it afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(GlyphFile, TheTamilLetterNaLoadsAsThreeStrokesAbout25MillimetresTall) {
  const Glyph na = loadGlyph(defaultDataDir() / "glyphs" / "na.json");
  EXPECT_EQ(na.name, "na");
  EXPECT_EQ(na.unicode, "U+0BA8");
  EXPECT_EQ(na.character, "ந");
  ASSERT_EQ(na.strokes.size(), 3u);
  double y_min = 1.0, y_max = -1.0;
  for (const auto& stroke : na.strokes) {
    EXPECT_GE(stroke.points.size(), 2u);
    EXPECT_FALSE(stroke.note.empty());
    for (const Vec2& p : stroke.points) {
      EXPECT_LE(std::abs(p.x()), 0.015) << "x in [-15, 15] mm";
      EXPECT_LE(std::abs(p.y()), 0.015) << "y in [-15, 15] mm";
      y_min = std::min(y_min, p.y());
      y_max = std::max(y_max, p.y());
    }
  }
  EXPECT_NEAR(y_max - y_min, 0.025, 0.002);
}

TEST(GlyphFile, ASecondSkillIsJustAnotherDataFile) {
  const Glyph loop = loadGlyph(defaultDataDir() / "glyphs" / "loop.json");
  EXPECT_EQ(loop.name, "loop");
  EXPECT_EQ(loop.unicode, "");
  ASSERT_EQ(loop.strokes.size(), 1u);
  EXPECT_GT(glyphPathLength(loop), 0.03);
}

TEST(GlyphFile, MillimetresAreConvertedToMetresOnLoading) {
  const Glyph g = parseGlyph(glyphText(R"([{"points": [[1.5, -2], [0, 12.25]]}])"), "t.json");
  ASSERT_EQ(g.strokes.size(), 1u);
  EXPECT_DOUBLE_EQ(g.strokes[0].points[0].x(), 0.0015);
  EXPECT_DOUBLE_EQ(g.strokes[0].points[0].y(), -0.002);
  EXPECT_DOUBLE_EQ(g.strokes[0].points[1].y(), 0.01225);
  EXPECT_DOUBLE_EQ(glyphPathLength(g), std::hypot(0.0015, 0.01425));
}

TEST(GlyphFile, ABadPointIsReportedWithTheFileTheStrokeAndThePoint) {
  const std::string message = glyphError(glyphText(R"([{"points": [[0, 0], [1, 1]]},
                                                      {"points": [[0, 0], [1, 1], [2, "a"]]}])"));
  EXPECT_THAT(message, HasSubstr("bad.json: stroke 2, point 3"));
  EXPECT_THAT(message, HasSubstr("expected [x_mm, y_mm]"));
  EXPECT_THAT(message, HasSubstr(R"([2,"a"])"));
}

TEST(GlyphFile, PointsMustBeTwoFiniteNumbersWithinTheLimit) {
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0, 0], [1, 2, 3]]}])")), HasSubstr("stroke 1, point 2"));
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0, 0], [60, 0]]}])")), HasSubstr("within ±50 mm, got [60,0]"));
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0, 0], 7]}])")), HasSubstr("point 2"));
}

TEST(GlyphFile, AStrokeNeedsTwoDistinctConsecutivePoints) {
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0, 0]]}])")),
              HasSubstr("stroke 1: key points: expected a list of at least two"));
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0, 0], [1, 1], [1, 1]]}])")),
              HasSubstr("stroke 1, point 3: expected a point different from point 2"));
}

TEST(GlyphFile, FormatVersionNameStrokesAndKeysAreChecked) {
  EXPECT_THAT(glyphError("{"), HasSubstr("bad.json: not valid JSON"));
  EXPECT_THAT(glyphError(R"({"format": "x", "version": 1, "name": "t", "strokes": []})"),
              HasSubstr("key format: expected \"hattr-glyph\""));
  EXPECT_THAT(glyphError(R"({"format": "hattr-glyph", "version": 2, "name": "t", "strokes": []})"),
              HasSubstr("key version: expected 1, got 2"));
  EXPECT_THAT(glyphError(R"({"format": "hattr-glyph", "version": 1, "strokes": [{"points": [[0,0],[1,1]]}]})"),
              HasSubstr("key name: expected a non-empty string"));
  EXPECT_THAT(glyphError(glyphText("[]")), HasSubstr("key strokes: expected a non-empty list"));
  EXPECT_THAT(glyphError(glyphText(R"([{"points": [[0,0],[1,1]]}])", R"("colour": "red", )")),
              HasSubstr("unknown key \"colour\""));
  EXPECT_THAT(glyphError(glyphText(R"([{"pts": [[0,0],[1,1]]}])")), HasSubstr("stroke 1: unknown key \"pts\""));
  EXPECT_THAT(glyphError(R"({"format": "hattr-glyph", "version": 1, "name": "t", "unicode": "0BA8",
                             "strokes": [{"points": [[0,0],[1,1]]}]})"),
              HasSubstr("key unicode: expected \"U+\""));
}

TEST(GlyphFile, AMissingFileIsReportedByName) {
  const test::TempDir dir;
  try {
    (void)loadGlyph(dir / "none.json");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("none.json: cannot open for reading: No such file or directory"));
  }
}

// Issue 35: a glyph is named by its file, its built-in name or the character itself.
TEST(GlyphFile, AGlyphIsFoundByItsPathItsNameOrItsCharacter) {
  EXPECT_EQ(findGlyph("na").name, "na");
  EXPECT_EQ(findGlyph("ந").name, "na");
  EXPECT_EQ(findGlyph("loop").name, "loop");
  const test::TempDir dir;
  test::writeText(dir / "a.json", glyphText(R"([{"points": [[0, 0], [5, 5]]}])"));
  EXPECT_EQ(findGlyph((dir / "a.json").string()).strokes.size(), 1u);
  EXPECT_THAT([&] {
    try {
      (void)findGlyph((dir / "b.json").string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  }(), HasSubstr("b.json: cannot open for reading"));
  try {
    (void)findGlyph("zeta");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("glyph \"zeta\": no such file, and no built-in glyph has that name or character"));
    EXPECT_THAT(e.what(), HasSubstr("loop, na (ந)"));
  }
}

TEST(DataDir, TheEnvironmentVariableWinsAndMustNameADirectory) {
  const test::TempDir dir;
  {
    const ScopedEnv env("HATTR_DATA_DIR", dir.path().c_str());
    EXPECT_EQ(defaultDataDir(), dir.path());
  }
  {
    const std::string missing = (dir / "missing").string();
    const ScopedEnv env("HATTR_DATA_DIR", missing.c_str());
    try {
      (void)defaultDataDir();
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("HATTR_DATA_DIR: expected a directory"));
      EXPECT_THAT(e.what(), HasSubstr(missing));
    }
  }
  const ScopedEnv unset("HATTR_DATA_DIR", nullptr);
  EXPECT_TRUE(std::filesystem::is_regular_file(defaultDataDir() / "glyphs" / "na.json"))
      << "without the variable, the share/hattr folder the build stages beside this program";
}

}  // namespace
}  // namespace hattr::sim
