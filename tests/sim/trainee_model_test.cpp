// The trainee model file: every parameter stated with unit, range and source; bad files
// rejected with the key, the range and the value; subjects drawn reproducibly from the
// stated distributions.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/trainee_model.hpp"
#include "support/test_support.hpp"

namespace hattr::sim {
namespace {

using ::testing::HasSubstr;

std::filesystem::path modelFile() { return defaultDataDir() / "sim" / "trainee_model.json"; }

std::string modelText() {
  std::ifstream in(modelFile());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The shipped file with the first occurrence of `from` replaced by `to`.
std::string edited(const std::string& from, const std::string& to) {
  std::string text = modelText();
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("test edit: \"" + from + "\" not in the model file");
  return text.replace(at, from.size(), to);
}

std::string modelError(const std::string& text) {
  try {
    (void)parseTraineeModel(text, "model.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::vector<const ModelParameter*> allParameters(const TraineeModel& m) {
  return {&m.basis_count,     &m.basis_width_ratio, &m.projection_ridge,
          &m.fast_retention,  &m.fast_rate,         &m.slow_retention,
          &m.slow_rate,       &m.weber_fraction,    &m.felt_force_stiffness_N_per_m,
          &m.position_noise_coefficient, &m.force_noise_coefficient, &m.deviation_rms_m,
          &m.force_scale,     &m.force_offset_N,    &m.pace_cv};
}

TEST(TraineeModelFile, TheShippedModelStatesEveryParameterWithARangeAndASource) {
  const TraineeModel model = loadTraineeModel(modelFile());
  EXPECT_EQ(model.version, 1);
  for (const ModelParameter* p : allParameters(model)) {
    EXPECT_FALSE(p->key.empty());
    EXPECT_LE(p->min, p->value) << p->key;
    EXPECT_LE(p->value, p->max) << p->key;
    EXPECT_FALSE(p->source.empty()) << p->key;
  }
  // The fast process forgets and learns faster than the slow one (Smith et al. 2006).
  EXPECT_LT(model.fast_retention.value, model.slow_retention.value);
  EXPECT_GT(model.fast_rate.value, model.slow_rate.value);
  // Millimetres in the file, metres inside.
  EXPECT_EQ(model.deviation_rms_m.key, "deviation_rms_mm");
  EXPECT_DOUBLE_EQ(model.deviation_rms_m.value, 0.002);
  EXPECT_DOUBLE_EQ(model.deviation_rms_m.max, 0.008);
}

TEST(TraineeModelFile, AValueOutsideItsRangeIsReportedWithKeyRangeAndValue) {
  const std::string message = modelError(edited(R"("value": 0.59)", R"("value": 0.95)"));
  EXPECT_THAT(message, HasSubstr("model.json: parameters.fast_retention.value"));
  EXPECT_THAT(message, HasSubstr("[0.2, 0.9]"));
  EXPECT_THAT(message, HasSubstr("got 0.95"));
}

TEST(TraineeModelFile, ARangeBeyondWhatTheModelCanUseIsRejected) {
  EXPECT_THAT(modelError(edited(R"("range": [0.2, 0.9])", R"("range": [0.2, 1.5])")),
              HasSubstr("parameters.fast_retention.range: expected [min, max] with 0 <= min <= max <= 1"));
}

TEST(TraineeModelFile, MissingUnknownAndMalformedEntriesAreRejected) {
  EXPECT_THAT(modelError(edited(R"("force_offset_N": {)", R"("force_offset_x": {)")),
              HasSubstr("unknown parameter \"parameters.force_offset_x\""));
  EXPECT_THAT(modelError(edited(R"("unit": "mm")", R"("unit": "m")")),
              HasSubstr("parameters.deviation_rms_mm.unit: expected \"mm\", got \"m\""));
  EXPECT_THAT(modelError(edited(R"("source": "assumption: a novice)", R"("source": "", "x": "a novice)")),
              HasSubstr("parameters.deviation_rms_mm: unknown field \"x\""));
  EXPECT_THAT(modelError(edited(R"("source": "Jones 1989)", R"("source": "Jones, Matching)")),
              HasSubstr("parameters.weber_fraction.source: expected \"Author year, short title\" or \"assumption: "));
  EXPECT_THAT(modelError(edited(R"({"kind": "lognormal", "sigma_log": 0.4})", R"({"kind": "uniform"})")),
              HasSubstr("parameters.deviation_rms_mm.per_subject.kind: expected one of fixed, normal"));
  EXPECT_THAT(modelError(edited(R"({"kind": "lognormal", "sigma_log": 0.4})", R"({"kind": "lognormal", "sigma_log": -1})")),
              HasSubstr("per_subject.sigma_log: expected a number in [0, 10], got -1"));
  EXPECT_THAT(modelError(edited(R"("value": 30)", R"("value": 30.5)")),
              HasSubstr("parameters.basis_count.value: expected an integer, got 30.5"));
  EXPECT_THAT(modelError(edited(R"("version": 1)", R"("version": 2)")), HasSubstr("key version: expected 1, got 2"));
  EXPECT_THAT(modelError("[]"), HasSubstr("expected a JSON object"));
}

TEST(TraineeModelFile, TheBasisIsTheSameForEverySubject) {
  std::string varying = modelText();
  const std::string fixed = R"({"kind": "fixed"})";  // basis_count's, the first in the file
  varying.replace(varying.find(fixed), fixed.size(), R"({"kind": "normal", "sd": 1})");
  EXPECT_THAT(modelError(varying), HasSubstr("parameters.basis_count.per_subject.kind: expected fixed"));
}

TEST(TraineeModelFile, AParameterMayCarryANote) {
  const std::string with_note =
      edited(R"("value": 30, "unit": "1",)", R"("note": "resolution of the plan", "value": 30, "unit": "1",)");
  EXPECT_NO_THROW((void)parseTraineeModel(with_note, "model.json"));
}

TEST(TraineeModelFile, TheFastProcessMustStayFasterThanTheSlowOne) {
  const std::string fast_from = R"("value": 0.21, "unit": "1", "range": [0.05, 0.6])";
  const std::string slow_from = R"("value": 0.02, "unit": "1", "range": [0.002, 0.1])";
  std::string text = modelText();
  text.replace(text.find(fast_from), fast_from.size(), R"("value": 0.06, "unit": "1", "range": [0.05, 0.6])");
  EXPECT_NO_THROW((void)parseTraineeModel(text, "model.json")) << "B_f = 0.06 >= B_s = 0.02";
  text.replace(text.find(slow_from), slow_from.size(), R"("value": 0.08, "unit": "1", "range": [0.002, 0.1])");
  EXPECT_THAT(modelError(text), HasSubstr("parameters.fast_rate: expected at least slow_rate = 0.08, got 0.06"));
}

TEST(DrawSubject, TheSameSeedGivesTheSameSubjectAndEveryDrawStaysInRange) {
  const TraineeModel model = loadTraineeModel(modelFile());
  EXPECT_EQ(drawSubject(model, 7), drawSubject(model, 7));
  EXPECT_NE(drawSubject(model, 7), drawSubject(model, 8));
  for (std::uint64_t seed = 0; seed < 300; ++seed) {
    const SubjectTraits t = drawSubject(model, seed);
    EXPECT_NO_THROW(validateTraits(t)) << "seed " << seed;
    EXPECT_GE(t.deviation_rms_m, model.deviation_rms_m.min) << "seed " << seed;
    EXPECT_LE(t.deviation_rms_m, model.deviation_rms_m.max) << "seed " << seed;
    EXPECT_GE(t.fast_retention, model.fast_retention.min) << "seed " << seed;
    EXPECT_LE(t.slow_retention, model.slow_retention.max) << "seed " << seed;
    EXPECT_EQ(t.felt_force_stiffness_N_per_m, model.felt_force_stiffness_N_per_m.value) << "fixed";
  }
  EXPECT_EQ(populationTraits(model).fast_rate, 0.21);
}

TEST(DrawSubject, DrawsFollowTheStatedDistributions) {
  const TraineeModel model = loadTraineeModel(modelFile());
  const std::uint64_t seed = test::testSeed(41);
  SCOPED_TRACE(::testing::Message() << "seed " << seed << " (set HATTR_TEST_SEED to repeat)");
  constexpr int kSubjects = 4000;
  std::vector<double> log_deviation, offset, complement;
  for (int i = 0; i < kSubjects; ++i) {
    const SubjectTraits t = drawSubject(model, seed * 100'003 + static_cast<std::uint64_t>(i));
    log_deviation.push_back(std::log(t.deviation_rms_m));
    offset.push_back(t.force_offset_N);
    complement.push_back(std::log(1.0 - t.fast_retention));
  }
  const auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
  };
  const auto sd = [&](const std::vector<double>& v) {
    const double m = mean(v);
    double s = 0.0;
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / static_cast<double>(v.size() - 1));
  };
  // lognormal: ln x ~ N(ln value, sigma_log²) (the range cuts off less than 0.1 % here).
  EXPECT_NEAR(mean(log_deviation), std::log(0.002), 0.03);
  EXPECT_NEAR(sd(log_deviation), 0.4, 0.03);
  // normal: mean value, sd in the parameter's unit.
  EXPECT_NEAR(mean(offset), 0.0, 0.01);
  EXPECT_NEAR(sd(offset), 0.15, 0.01);
  // lognormal_complement: ln(1 − A_f) ~ N(ln(1 − 0.59), 0.3²), cut by the range [0.2, 0.9]
  // only beyond about 2.3 sigma on one side: the median holds.
  std::sort(complement.begin(), complement.end());
  EXPECT_NEAR(complement[complement.size() / 2], std::log(1.0 - 0.59), 0.03);
}

TEST(SubjectTraits, InvalidTraitsAreRejectedByName) {
  SubjectTraits t = populationTraits(loadTraineeModel(modelFile()));
  t.fast_retention = 0.999;
  try {
    validateTraits(t);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("fast_retention: expected at most slow_retention = 0.992, got 0.999"));
  }
  t = populationTraits(loadTraineeModel(modelFile()));
  t.position_noise_coefficient = -0.1;
  EXPECT_THROW(validateTraits(t), InputError);
}

}  // namespace
}  // namespace hattr::sim
