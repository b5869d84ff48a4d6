#include "hattr/render/world_config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/test_support.hpp"

namespace hattr::render {
namespace {

using ::testing::HasSubstr;

std::string configError(const std::string& json) {
  try {
    (void)parseWorldConfig(json, "world.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(WorldConfig, AbsentKeysKeepTheirDefaults) {
  const WorldConfig c = parseWorldConfig(R"({"friction": {"static": 0.5}, "writing_angle_deg": 45})", "world.json");
  EXPECT_EQ(c.paper.friction.static_coefficient, 0.5);
  EXPECT_EQ(c.paper.friction.dynamic_coefficient, PaperParams{}.friction.dynamic_coefficient);
  EXPECT_NEAR(c.paper.writing_angle_rad, 0.785398163397448, 1e-12);
  EXPECT_EQ(c.relief.kind, ReliefConfig::Kind::kGrain);
}

TEST(WorldConfig, DefaultsRoundTripThroughTheirJson) {
  const WorldConfig c = parseWorldConfig(defaultWorldConfigJson(), "defaults.json");
  const WorldConfig d;
  EXPECT_EQ(c.paper.contact.stiffness_N_per_m, d.paper.contact.stiffness_N_per_m);
  EXPECT_EQ(c.paper.texture.seed, d.paper.texture.seed);
  EXPECT_EQ(c.relief.vertices, d.relief.vertices);
  EXPECT_NEAR(c.paper.writing_angle_rad, d.paper.writing_angle_rad, 1e-15);
}

TEST(WorldConfig, BadValuesNameKeyRangeAndValue) {
  EXPECT_EQ(configError(R"({"paper": {"stiffness_N_per_m": -5}})"),
            "world.json: key paper.stiffness_N_per_m: expected a number in [1, 1000000], got -5");
  EXPECT_EQ(configError(R"({"friction": {"static": 0.2, "dynamic": 0.3}})"),
            "world.json: key friction.dynamic: expected a number in [0, friction.static = 0.2], got 0.3");
  EXPECT_EQ(configError(R"({"texture": {"sigma": "lots"}})"),
            "world.json: key texture.sigma: expected a number in [0, 1], got \"lots\"");
  EXPECT_THAT(configError(R"({"paper": {"stifness_N_per_m": 5}})"),
              HasSubstr("world.json: unknown key \"paper.stifness_N_per_m\": expected one of stiffness_N_per_m"));
  EXPECT_THAT(configError(R"({"ink": 1})"), HasSubstr("unknown key \"ink\""));
  EXPECT_EQ(configError(R"({"relief": {"kind": "bumpy"}})"),
            "world.json: key relief.kind: expected one of flat, grain, pgm, got \"bumpy\"");
  EXPECT_EQ(configError(R"({"relief": {"kind": "pgm"}})"), "world.json: key relief.file: required when kind is pgm");
  EXPECT_EQ(configError(R"({"writing_angle_deg": 120})"),
            "world.json: key writing_angle_deg: expected a number in [10, 90], got 120");
  EXPECT_THAT(configError("{"), HasSubstr("world.json: not valid JSON"));
}

TEST(WorldConfig, LoadsAPgmReliefRelativeToTheConfig) {
  test::TempDir dir;
  test::writeText(dir / "relief.pgm", "P2\n# a ridge\n3 2\n255\n0 255 0\n0 255 0\n");
  test::writeText(dir / "world.json", R"({"relief": {"kind": "pgm", "file": "relief.pgm", "size_m": 0.002, "height_scale_m": 0.001}})");
  const WorldConfig c = loadWorldConfig(dir / "world.json");
  const HeightField relief = buildRelief(c.relief);
  ASSERT_EQ(relief.nx(), 3);
  EXPECT_NEAR(relief.heightAt(0.0, 0.0), 0.001, 1e-15);    // white in the middle
  EXPECT_NEAR(relief.heightAt(-0.001, 0.0), 0.0, 1e-15);   // black at the left edge
}

TEST(WorldConfig, BadPgmNamesTheProblem) {
  test::TempDir dir;
  test::writeText(dir / "bad.pgm", "P6\n3 2\n255\n");
  try {
    (void)HeightField::fromPgm(dir / "bad.pgm", 0.01, 0.001);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.pgm: not a grayscale PGM image: expected magic P2 or P5, got \"P6\""));
  }
  test::writeText(dir / "short.pgm", "P2\n3 2\n255\n0 1 2\n");
  EXPECT_THROW((void)HeightField::fromPgm(dir / "short.pgm", 0.01, 0.001), InputError);
}

}  // namespace
}  // namespace hattr::render
