// The letter library (issue 39): Latin a–z, A–Z and the digits 0–9 as built-in glyphs of hattr's
// print script, each found by its character, sitting on the school lines, with the model's stroke
// directions; and each written by the simulated expert on the simulated pen.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "hattr/session/trial.hpp"
#include "sim/expert_checks.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

// The school lines of the print script [mm]: the glyph files' documented geometry.
constexpr double kBaseline_mm = -10.0;
constexpr double kMidline_mm = 0.0;
constexpr double kTopLine_mm = 10.0;
constexpr double kDescender_mm = -17.0;

/// The 62 characters: a–z, A–Z, 0–9.
std::vector<std::string> letterCharacters() {
  std::vector<std::string> out;
  for (char c = 'a'; c <= 'z'; ++c) out.emplace_back(1, c);
  for (char c = 'A'; c <= 'Z'; ++c) out.emplace_back(1, c);
  for (char c = '0'; c <= '9'; ++c) out.emplace_back(1, c);
  return out;
}

/// The glyph's file name stem for a character: small-a, capital-a, digit-0.
std::string expectedName(char c) {
  const auto lower = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (std::islower(static_cast<unsigned char>(c)) != 0) return fmt::format("small-{}", c);
  if (std::isupper(static_cast<unsigned char>(c)) != 0) return fmt::format("capital-{}", lower);
  return fmt::format("digit-{}", c);
}


TEST(LetterLibrary, EveryLetterAndDigitIsABuiltInGlyphFoundByItsCharacter) {
  HATTR_STARTS_NO_THREAD();
  for (const std::string& c : letterCharacters()) {
    const Glyph glyph = findGlyph(c);
    EXPECT_EQ(glyph.character, c);
    EXPECT_EQ(glyph.name, expectedName(c[0])) << c;
    EXPECT_EQ(glyph.unicode, fmt::format("U+{:04X}", static_cast<int>(c[0]))) << c;
    EXPECT_EQ(findGlyph(glyph.name).character, c) << "by its name too";
  }
  // "a" and "A" are different glyphs, and no two files' names differ only in case (a
  // case-insensitive file system would keep one of them).
  EXPECT_NE(findGlyph("a").name, findGlyph("A").name);
  std::set<std::string> folded;
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(defaultDataDir() / "glyphs")) {
    std::string name = entry.path().filename().string();
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
    folded.insert(name);
    ++files;
  }
  EXPECT_EQ(folded.size(), files);
  EXPECT_EQ(builtInGlyphs().size(), 62u + 2u) << "the letters, the digits, ந and the loop";
  // An unknown name lists the library by its characters, not 62 names.
  EXPECT_THAT([] { (void)findGlyph("aa"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr(
                  "loop, na (ந), a letter or digit by its character "
                  "(ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789abcdefghijklmnopqrstuvwxyz) (hattr sim glyphs lists them)")));
}

TEST(LetterLibrary, EachGlyphSitsOnTheSchoolLines) {
  HATTR_STARTS_NO_THREAD();
  const std::string descenders = "gjpqy";
  const std::string ascenders = "bdfhklt";
  for (const std::string& c : letterCharacters()) {
    const GlyphBounds box = glyphBounds(findGlyph(c));
    const double top = units::metresToMillimetres(box.max.y()), bottom = units::metresToMillimetres(box.min.y());
    const double centre = units::metresToMillimetres(box.min.x() + box.max.x()) / 2.0;
    EXPECT_NEAR(centre, 0.0, 0.05) << c << " is centred on x = 0";
    EXPECT_LE(top, kTopLine_mm + 0.05) << c;
    const char ch = c[0];
    if (std::islower(static_cast<unsigned char>(ch)) != 0) {
      const bool descends = descenders.find(ch) != std::string::npos;
      const bool ascends = ascenders.find(ch) != std::string::npos;
      // Letters reach the baseline, or the descender line; short ones the midline, tall ones above it.
      if (descends) {
        EXPECT_NEAR(bottom, kDescender_mm, 0.05) << c;
      } else {
        EXPECT_NEAR(bottom, kBaseline_mm, 0.05) << c;
      }
      if (ascends) {
        EXPECT_GT(top, kMidline_mm + 5.0) << c;
      } else if (ch != 'i' && ch != 'j') {  // their dots are above the midline
        EXPECT_NEAR(top, kMidline_mm, 0.05) << c;
      }
    } else {
      // Capitals and digits stand from the baseline to the top line.
      EXPECT_NEAR(top, kTopLine_mm, 0.05) << c;
      EXPECT_NEAR(bottom, kBaseline_mm, 0.05) << c;
    }
  }
}

// The print model's directions: a stroke that starts with a vertical line starts at its top
// (pull down); one that starts with a horizontal line goes left to right (slide right).
TEST(LetterLibrary, StrokesArePulledDownAndSlidRight) {
  HATTR_STARTS_NO_THREAD();
  int vertical = 0, horizontal = 0;
  for (const std::string& c : letterCharacters()) {
    const Glyph glyph = findGlyph(c);
    for (std::size_t s = 0; s < glyph.strokes.size(); ++s) {
      const Vec2 d = glyph.strokes[s].points[1] - glyph.strokes[s].points[0];
      if (d.norm() < 3e-3) continue;  // dots and short curves
      if (std::abs(d.x()) < 0.1 * std::abs(d.y())) {
        EXPECT_LT(d.y(), 0.0) << c << " stroke " << s + 1 << " starts with a vertical line written upward";
        ++vertical;
      } else if (std::abs(d.y()) < 0.1 * std::abs(d.x())) {
        EXPECT_GT(d.x(), 0.0) << c << " stroke " << s + 1 << " starts with a horizontal line written leftward";
        ++horizontal;
      }
    }
  }
  EXPECT_GT(vertical, 30);
  EXPECT_GT(horizontal, 8);
}

// Circles go back (counter-clockwise) or forward (clockwise) as each stroke's note says: the
// stroke's turning, summed over its curve (turns under 90°; a retrace or a corner is not curve),
// is at least half a turn that way.
TEST(LetterLibrary, CirclesGoBackOrForwardAsTheModelSays) {
  HATTR_STARTS_NO_THREAD();
  int back = 0, forward = 0;
  for (const std::string& c : letterCharacters()) {
    const Glyph glyph = findGlyph(c);
    for (std::size_t s = 0; s < glyph.strokes.size(); ++s) {
      const auto& p = glyph.strokes[s].points;
      double turning = 0.0;
      for (std::size_t i = 1; i + 1 < p.size(); ++i) {
        const Vec2 u = p[i] - p[i - 1], v = p[i + 1] - p[i];
        const double turn = std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
        if (std::abs(turn) < std::numbers::pi / 2.0) turning += turn;
      }
      const std::string& note = glyph.strokes[s].note;
      if (note.find("circle back") != std::string::npos) {
        EXPECT_GT(turning, std::numbers::pi) << c << " stroke " << s + 1 << ": " << note;
        ++back;
      }
      if (note.find("circle forward") != std::string::npos) {
        EXPECT_LT(turning, -std::numbers::pi) << c << " stroke " << s + 1 << ": " << note;
        ++forward;
      }
    }
  }
  EXPECT_GE(back, 10);
  EXPECT_GE(forward, 2);
}

// The box of a glyph's via points, and a letter found before a file of the same name in the
// working folder (a file is still found when no built-in glyph has its name).
TEST(LetterLibrary, BoundsAndALetterBeforeAFileOfItsName) {
  HATTR_STARTS_NO_THREAD();
  const GlyphBounds a = glyphBounds(findGlyph("A"));
  EXPECT_NEAR(units::metresToMillimetres(a.min.x()), -6.5, 1e-9);
  EXPECT_NEAR(units::metresToMillimetres(a.max.x()), 6.5, 1e-9);
  EXPECT_NEAR(units::metresToMillimetres(a.min.y()), kBaseline_mm, 1e-9);
  EXPECT_NEAR(units::metresToMillimetres(a.max.y()), kTopLine_mm, 1e-9);
  const test::TempDir dir;
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  const std::string mine = R"({"format": "hattr-glyph", "version": 1, "name": "mine", "strokes": [{"points": [[0, 0], [5, 5]]}]})";
  test::writeText(dir / "a", mine);
  test::writeText(dir / "my-letter", mine);
  const std::string by_a = findGlyph("a").name;
  const std::string by_file = findGlyph("my-letter").name;
  std::filesystem::current_path(before);
  EXPECT_EQ(by_a, "small-a");
  EXPECT_EQ(by_file, "mine");
}

/// One glyph of the library written by the simulated expert on the simulated pen.
class LetterWritten : public ::testing::TestWithParam<std::string> {};

// Under the sanitizers every seventh glyph (9 of 62): the same path over other data; the
// release build writes them all (docs/architecture.md).
bool writtenUnderTheSanitizers(const std::string& c) {
  const auto all = letterCharacters();
  return (std::find(all.begin(), all.end(), c) - all.begin()) % 7 == 0;
}

TEST_P(LetterWritten, ByTheSimulatedExpertOnTheSimulatedPen) {
  HATTR_STARTS_NO_THREAD();
  if (test::kSanitized && !writtenUnderTheSanitizers(GetParam())) {
    GTEST_SKIP() << "left to the release build under the sanitizers: every seventh glyph is written here";
  }
  const Glyph glyph = findGlyph(GetParam());
  const HapticProfile script = expertScript(glyph);
  checks::expectPassesEveryViaPointInOrder(glyph, script);
  // Played on the simulated pen, the recording follows the script.
  render::WorldConfig world;
  world.relief.kind = render::ReliefConfig::Kind::kFlat;
  session::TrialEnvironment environment("sim://pen", world, 1000.0);
  const HapticProfile expert = recordExpert(environment, script, {.subject = "expert", .skill = glyph.name});
  checks::expectRecordingFollowsScript(script, expert, 200);
}

INSTANTIATE_TEST_SUITE_P(Library, LetterWritten, ::testing::ValuesIn(letterCharacters()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           std::string name = expectedName(param.param[0]);
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

}  // namespace
}  // namespace hattr::sim
