#include "hattr/io/profile_csv.hpp"

#include <cstring>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/test_support.hpp"

namespace hattr::io {
namespace {

using ::testing::HasSubstr;

constexpr const char* kHeader = "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n";

std::string readError(const std::string& text) {
  std::istringstream in(text);
  try {
    (void)readProfileCsv(in, "bad.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// ---- Round trip ------------------------------------------------------------------------

TEST(ProfileCsv, RoundTripIsBitForBitWithAndWithoutRawChannels) {
  const std::uint64_t seed = test::testSeed(20261121);
  std::mt19937_64 rng(seed);
  for (const RawChannels raw : {RawChannels{}, RawChannels{true, false}, RawChannels{true, true}}) {
    const HapticProfile original = test::randomProfile(rng, 500, raw);
    std::stringstream text;
    writeProfileCsv(original, text);
    const HapticProfile back = readProfileCsv(text, "roundtrip.csv");
    ASSERT_EQ(back, original) << "seed " << seed;
    for (std::size_t i = 0; i < original.size(); ++i) {
      for (const auto& info : allChannels()) {
        if (info.derived || !original.hasChannel(info.channel)) continue;
        ASSERT_TRUE(sameBits(channelValue(back[i], info.channel), channelValue(original[i], info.channel)))
            << "seed " << seed << " sample " << i << " channel " << info.name;
      }
    }
  }
}

TEST(ProfileCsv, FileRoundTripIsExactAndRefusesToOverwrite) {
  test::TempDir dir;
  std::mt19937_64 rng(test::testSeed(7));
  const HapticProfile original = test::randomProfile(rng, 50, RawChannels{true, true});
  writeProfileCsv(original, dir / "p.csv");
  EXPECT_EQ(readProfileCsv(dir / "p.csv"), original);

  // A second write to the same name keeps the first file intact.
  const std::string before = test::readText(dir / "p.csv");
  const HapticProfile other = test::randomProfile(rng, 5, RawChannels{});
  try {
    writeProfileCsv(other, dir / "p.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("already exists; refusing to overwrite it"));
  }
  EXPECT_EQ(test::readText(dir / "p.csv"), before);
  writeProfileCsv(other, dir / "p.csv", Overwrite::kReplace);
  EXPECT_EQ(readProfileCsv(dir / "p.csv"), other);
  // No temporary files are left behind.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

TEST(ProfileCsv, ReadsMillimetresAndMillisecondsIntoSiAndFillsVelocity) {
  const std::string text =
      "# subject: S1\n"
      "t_ms,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,pen_down_bool\n"
      "0,0,0,0,0,0,-1,1\n"
      "10,1,0,0,0,0,-1,1\n"
      "20,2,0,0,0,0,-1,0\n";
  std::istringstream in(text);
  const HapticProfile p = readProfileCsv(in, "mm.csv");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_DOUBLE_EQ(p[1].t_s, 0.010);
  EXPECT_DOUBLE_EQ(p[2].p_WT.x(), 0.002);
  EXPECT_NEAR(p[1].v_WT.x(), 0.1, 1e-12);  // 1 mm per 10 ms
  EXPECT_TRUE(p[0].in_contact);             // contact follows pen_down when absent
  EXPECT_FALSE(p[2].in_contact);
  EXPECT_EQ(p.metadata().subject, "S1");
}

TEST(ProfileCsv, KeepsUnknownMetadataKeysAndSkipsComments) {
  const std::string text = std::string("# a free comment line\n# mode: alpha\n# trial: 4\n") + kHeader +
                           "0,0,0,0,0,0,0,1\n";
  std::istringstream in(text);
  const HapticProfile p = readProfileCsv(in, "meta.csv");
  EXPECT_EQ(p.metadata().extra.at("mode"), "alpha");
  EXPECT_EQ(p.metadata().extra.at("trial"), "4");
  EXPECT_EQ(p.metadata().extra.size(), 2u);
}

TEST(ProfileCsv, MetadataKeysNamedLikeChannelsRoundTrip) {
  // Found by the fuzzer: the reader accepted "# t: ..." and the writer refused to write it back.
  const std::string text = std::string("# t: 1\n# fz: x\n") + kHeader + "0,0,0,0,0,0,0,1\n";
  std::istringstream in(text);
  const HapticProfile p = readProfileCsv(in, "keys.csv");
  std::stringstream again;
  writeProfileCsv(p, again);
  EXPECT_EQ(readProfileCsv(again, "again.csv"), p);
}

// ---- One test per class of bad input ---------------------------------------------------

TEST(ProfileCsvErrors, EmptyFile) {
  EXPECT_EQ(readError(""), "bad.csv: empty file: expected '# key: value' metadata lines, a column row and data");
}

TEST(ProfileCsvErrors, MetadataButNoColumnRow) {
  EXPECT_EQ(readError("# subject: x\n"),
            "bad.csv:1: expected a column row (t_s,x_m,...), got the end of the file");
}

TEST(ProfileCsvErrors, NoDataRows) {
  EXPECT_EQ(readError(kHeader), "bad.csv: no data rows after the column row");
}

TEST(ProfileCsvErrors, WrongColumnCount) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,0,1\n0.1,0,0,0,0,0,1\n"),
            "bad.csv:3: expected 8 fields, got 7");
}

TEST(ProfileCsvErrors, NonNumericValue) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,abc,1\n"),
            "bad.csv:2: column 7 (fz_N): expected a number, got \"abc\"");
}

// Values no pen on paper produces are refused with the line, the column and the bound; the
// bound applies in SI, whatever unit the column is in (1200 mm is 1.2 m).
TEST(ProfileCsvErrors, PhysicallyAbsurdValues) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,0,1\n0.1,1e150,0,0,0,0,0,1\n"),
            "bad.csv:3: column 2 (x_m): expected at most 1 m in magnitude (a pen's workspace is well under a metre), "
            "got \"1e150\"");
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,-1500,1\n"),
            "bad.csv:2: column 7 (fz_N): expected at most 1000 N in magnitude (a hand on a pen exerts well under a "
            "kilonewton), got \"-1500\"");
  EXPECT_THAT(readError("t_s,x_mm,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,1200,0,0,0,0,0,1\n"),
              HasSubstr("bad.csv:2: column 2 (x_mm): expected at most 1 m in magnitude"));
  // At the bound is still a (strange but possible) profile.
  EXPECT_EQ(readError(std::string(kHeader) + "0,1,-1,0.5,1000,0,-1000,1\n"), "(no error)");
}

TEST(ProfileCsvErrors, EmptyField) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,,0,0,0,0,0,1\n"),
            "bad.csv:2: column 2 (x_m): expected a number, got \"\"");
}

TEST(ProfileCsvErrors, NonFiniteValue) {
  EXPECT_EQ(readError(std::string("# subject: s\n") + kHeader + "0,0,0,0,0,0,0,1\n0.1,0,0,0,0,0,nan,1\n"),
            "bad.csv:4: column 7 (fz_N): expected a finite number, got \"nan\"");
  EXPECT_THAT(readError(std::string(kHeader) + "0,inf,0,0,0,0,0,1\n"), HasSubstr("got \"inf\""));
}

TEST(ProfileCsvErrors, TimeNotStrictlyIncreasing) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,0,1\n0.5,0,0,0,0,0,0,1\n0.5,0,0,0,0,0,0,1\n"),
            "bad.csv:4: column 1 (t_s): time must increase strictly: expected > 0.5, got 0.5");
}

TEST(ProfileCsvErrors, MissingRequiredColumn) {
  EXPECT_EQ(readError("t_s,x_m,y_m,z_m,fx_N,fy_N,pen_down_bool\n0,0,0,0,0,0,1\n"),
            "bad.csv:1: missing required column(s): fz (got \"t_s,x_m,y_m,z_m,fx_N,fy_N,pen_down_bool\")");
}

TEST(ProfileCsvErrors, UnknownUnit) {
  EXPECT_EQ(readError("t_s,x_in,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,1\n"),
            "bad.csv:1: column 2 (x_in): unknown unit for x: expected one of m, mm, got \"in\"");
}

TEST(ProfileCsvErrors, UnknownChannel) {
  EXPECT_THAT(readError("t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool,temp_C\n0,0,0,0,0,0,0,1,20\n"),
              HasSubstr("bad.csv:1: column 9: expected a channel name followed by _unit"));
}

TEST(ProfileCsvErrors, DuplicateColumn) {
  EXPECT_EQ(readError("t_s,x_m,x_mm,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,0,1\n"),
            "bad.csv:1: column 3 (x_mm): channel x appears twice");
}

TEST(ProfileCsvErrors, FlagThatIsNotZeroOrOne) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,0,2\n"),
            "bad.csv:2: column 8 (pen_down_bool): expected 0 or 1, got \"2\"");
}

TEST(ProfileCsvErrors, NewerFormatVersion) {
  EXPECT_EQ(readError(std::string("# format: hattr-profile/2\n") + kHeader + "0,0,0,0,0,0,0,1\n"),
            "bad.csv:1: format: expected \"hattr-profile/1\", got \"hattr-profile/2\"");
}

TEST(ProfileCsvErrors, BadNominalRate) {
  EXPECT_EQ(readError(std::string("# rate_hz: fast\n") + kHeader + "0,0,0,0,0,0,0,1\n"),
            "bad.csv:1: rate_hz: expected a finite number >= 0, got \"fast\"");
}

TEST(ProfileCsvErrors, ControlCharacterInMetadata) {
  // Found by the fuzzer: a carriage return inside a value could not be written back.
  EXPECT_EQ(readError(std::string("# subject: a\rb\n") + kHeader + "0,0,0,0,0,0,0,1\n"),
            "bad.csv:1: expected printable metadata text, got a control character");
}

TEST(ProfileCsvErrors, BlankLineInsideTheData) {
  EXPECT_EQ(readError(std::string(kHeader) + "0,0,0,0,0,0,0,1\n\n0.1,0,0,0,0,0,0,1\n"),
            "bad.csv:4: expected a data row, got a blank line before it");
}

TEST(ProfileCsvErrors, MissingFileNamesTheFile) {
  try {
    (void)readProfileCsv(std::filesystem::path("/nonexistent/p.csv"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/p.csv: cannot open for reading: No such file or directory");
  }
}

TEST(ProfileCsvWrite, RefusesMetadataThatCannotBeReadBack) {
  HapticProfile p;
  p.append(Sample{});
  p.metadata().extra["bad key"] = "x";
  std::ostringstream out;
  EXPECT_THROW(writeProfileCsv(p, out), InputError);
  p.metadata().extra.clear();
  p.metadata().subject = "two\nlines";
  EXPECT_THROW(writeProfileCsv(p, out), InputError);
  EXPECT_THROW(writeProfileCsv(HapticProfile{}, out), InputError);
}

}  // namespace
}  // namespace hattr::io
