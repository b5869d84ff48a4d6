// The simulated trainee: its hand plays its plan; its one learning rule follows the two-state
// model; what it felt moves its plan the way the force pushed; perception and motor noise have
// the stated sizes; the same seeds give the same trainee. Most tests use a kinematic stand-in
// for a trial (a recording made directly from the plan, no physics) so they stay fast; the last
// two run real trials on the simulated pen.

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include "hattr/core/error.hpp"
#include "hattr/guidance/reference.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/trainee.hpp"
#include "sim/shipped_model.hpp"
#include "sim/trainee_internal.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

constexpr double kAltitude = std::numbers::pi / 3.0;

/// A template with the pen down throughout: a smooth figure over `duration_s` at 1 kHz,
/// pressing with a normal force of 1 N at 60°, scaled by `scale` in the plane.
HapticProfile penDownTemplate(double duration_s = 1.0, double scale = 1.0) {
  HapticProfile p(ProfileMetadata{.subject = "expert", .skill = "figure"}, RawChannels{.tilt = true});
  const auto n = static_cast<int>(std::lround(duration_s * 1000.0));
  const double w = 2.0 * std::numbers::pi / duration_s;
  for (int i = 0; i <= n; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    s.p_WT = scale * Vec3(0.01 * std::sin(w * s.t_s), 0.005 * std::sin(2.0 * w * s.t_s), 0.0);
    s.v_WT = scale * Vec3(0.01 * w * std::cos(w * s.t_s), 0.01 * w * std::cos(2.0 * w * s.t_s), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = s.in_contact = true;
    s.tilt_altitude_rad = kAltitude;
    s.tilt_azimuth_rad = 2.356194490192345;
    p.append(s);
  }
  return p;
}

/// The shipped model with a negligible ridge, so projections of fields on the basis are exact.
TraineeModel exactModel() {
  TraineeModel model = test::shippedModel();
  model.projection_ridge.value = 1e-12;
  return model;
}

/// The population's traits without motor or perception noise.
SubjectTraits quietTraits() {
  SubjectTraits t = populationTraits(test::shippedModel());
  t.position_noise_coefficient = 0.0;
  t.force_noise_coefficient = 0.0;
  t.weber_fraction = 0.0;
  t.pace_cv = 0.0;  // every trial at the plan's pace, so a trial and its plan share one clock
  return t;
}

/// RMS distance in the plane between two profiles on the same grid [m].
double rmsDistance(const HapticProfile& a, const HapticProfile& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i].p_WT.head<2>() - b[i].p_WT.head<2>()).squaredNorm();
  return std::sqrt(sum / static_cast<double>(a.size()));
}

/// A kinematic stand-in for a trial: the plan itself as the recording, with a guidance force.
HapticProfile standIn(const SimulatedTrainee& trainee, const Vec3& f_guide_W = Vec3::Zero()) {
  const HapticProfile plan = trainee.plan();
  HapticProfile recorded(plan.metadata(), plan.rawChannels());
  for (Sample s : plan.samples()) {
    s.f_guide_W = f_guide_W;
    recorded.append(s);
  }
  return recorded;
}

/// The two-state model on one scalar error: the plan error after each trial, relative to the
/// first, when the error is seen in full every trial (Smith et al. 2006).
std::vector<double> twoStateErrors(const SubjectTraits& t, int trials) {
  std::vector<double> errors{1.0};
  double fast = 0.0, slow = 0.0;
  for (int n = 0; n < trials; ++n) {
    const double e = -(1.0 + fast + slow);
    fast = t.fast_retention * fast + t.fast_rate * e;
    slow = t.slow_retention * slow + t.slow_rate * e;
    errors.push_back(1.0 + fast + slow);
  }
  return errors;
}

TEST(SimulatedTrainee, WithoutNoiseOrDeviationTheHandPlaysTheTemplate) {
  const HapticProfile script = expertScript(loadGlyph(defaultDataDir() / "glyphs" / "loop.json"));
  SubjectTraits traits = quietTraits();
  traits.deviation_rms_m = 0.0;
  const SimulatedTrainee trainee(test::shippedModel(), traits, script, 1);
  const auto hand = trainee.handForTrial(1);
  device::ProfileHandScript reference(script);
  for (double t = 0.0; t < script.duration_s() + 0.5; t += 0.00025) {
    const device::HandCommand a = hand->command(t);
    const device::HandCommand b = reference.command(t);
    ASSERT_LT((a.p_target_W - b.p_target_W).norm(), 1e-15) << "t = " << t;
    ASSERT_LT((a.v_target_W - b.v_target_W).head<2>().norm(), 1e-12) << "t = " << t;
    ASSERT_EQ(a.v_target_W.z(), 0.0) << "the hand holds or presses; it tracks no vertical speed";
    ASSERT_NEAR(a.press_N, b.press_N, 1e-12) << "t = " << t;
    ASSERT_EQ(a.pen_down, b.pen_down) << "t = " << t;
    ASSERT_EQ(a.altitude_rad, b.altitude_rad);
    ASSERT_EQ(a.azimuth_rad, b.azimuth_rad);
  }
}

TEST(SimulatedTrainee, StartsFromTheTemplatePlusASmoothPersonalDeviationOfItsRms) {
  const HapticProfile tmpl = penDownTemplate();
  SubjectTraits traits = quietTraits();
  traits.deviation_rms_m = 0.003;
  const std::uint64_t seed = test::testSeed(5);
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  const SimulatedTrainee trainee(test::shippedModel(), traits, tmpl, seed);
  const HapticProfile plan = trainee.plan();
  EXPECT_NEAR(rmsDistance(plan, tmpl), 0.003, 1e-12);
  // Smooth: the offset varies on the basis's time scale σ·T, not from sample to sample: its
  // largest step over dt is a few RMS times dt / (σ·T).
  double largest_step = 0.0;
  for (std::size_t i = 1; i < plan.size(); ++i) {
    const Vec3 step = (plan[i].p_WT - tmpl[i].p_WT) - (plan[i - 1].p_WT - tmpl[i - 1].p_WT);
    largest_step = std::max(largest_step, step.norm());
  }
  const double width_s = trainee.basis().width() * trainee.duration_s();
  EXPECT_LT(largest_step, 5.0 * 0.003 * 0.001 / width_s);
  EXPECT_EQ(trainee.fastState().norm(), 0.0);
  EXPECT_EQ(trainee.slowState().norm(), 0.0);
}

TEST(SimulatedTrainee, TheSameSeedsGiveTheSameTraineeAndTheSameTrials) {
  const HapticProfile tmpl = penDownTemplate(0.5);
  const SubjectTraits traits = drawSubject(test::shippedModel(), 3);
  SimulatedTrainee a(test::shippedModel(), traits, tmpl, 77), b(test::shippedModel(), traits, tmpl, 77);
  const SimulatedTrainee other(test::shippedModel(), traits, tmpl, 78);
  EXPECT_TRUE(a.plan() == b.plan());
  EXPECT_FALSE(a.plan() == other.plan());
  const auto ha = a.handForTrial(9), hb = b.handForTrial(9), hc = a.handForTrial(10);
  double same = 0.0, different = 0.0;
  for (double t = 0.0; t < 0.5; t += 0.001) {
    same = std::max(same, (ha->command(t).p_target_W - hb->command(t).p_target_W).norm());
    different = std::max(different, (ha->command(t).p_target_W - hc->command(t).p_target_W).norm());
  }
  EXPECT_EQ(same, 0.0);
  EXPECT_GT(different, 1e-5) << "another trial seed, other noise";
  const HapticProfile recorded = standIn(a, Vec3(0.2, 0.0, -0.1));
  a.learn(recorded, true);
  b.learn(recorded, true);
  EXPECT_EQ(a.fastState(), b.fastState());
  EXPECT_EQ(a.slowState(), b.slowState());
  EXPECT_EQ(a.trialsLearned(), 1);
}

TEST(SimulatedTrainee, SeeingTheTemplateShrinksThePlanErrorAsTheTwoStateModelPredicts) {
  const HapticProfile tmpl = penDownTemplate();
  const SubjectTraits traits = quietTraits();
  const std::uint64_t seed = test::testSeed(11);
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  SimulatedTrainee trainee(exactModel(), traits, tmpl, seed);
  const double initial = rmsDistance(trainee.plan(), tmpl);
  const std::vector<double> predicted = twoStateErrors(traits, 11);
  double previous = initial;
  for (int n = 1; n <= 11; ++n) {
    trainee.learn(standIn(trainee), true);
    const double error = rmsDistance(trainee.plan(), tmpl);
    EXPECT_NEAR(error / initial, predicted[static_cast<std::size_t>(n)], 1e-6) << "after trial " << n;
    EXPECT_LT(error, previous) << "after trial " << n;
    previous = error;
  }
  EXPECT_LT(previous, 0.6 * initial);
}

TEST(SimulatedTrainee, WithTheTemplateHiddenAndNoGuidanceEachStateDecaysByItsRetention) {
  const HapticProfile tmpl = penDownTemplate();
  const SubjectTraits traits = drawSubject(test::shippedModel(), 12);
  SimulatedTrainee trainee(test::shippedModel(), traits, tmpl, 12);
  for (int n = 0; n < 3; ++n) trainee.learn(standIn(trainee), true);
  const PlanWeights fast = trainee.fastState();
  const PlanWeights slow = trainee.slowState();
  ASSERT_GT(slow.norm(), 0.0);
  trainee.learn(standIn(trainee), false);
  EXPECT_LT((trainee.fastState() - traits.fast_retention * fast).cwiseAbs().maxCoeff(), 1e-18);
  EXPECT_LT((trainee.slowState() - traits.slow_retention * slow).cwiseAbs().maxCoeff(), 1e-18);
}

// Between sessions on different days the fast state is forgotten and the slow state kept
// (Joiner & Smith 2008); within a day nothing changes.
TEST(SimulatedTrainee, DaysBetweenSessionsForgetTheFastStateAndKeepTheSlow) {
  const HapticProfile tmpl = penDownTemplate();
  SimulatedTrainee trainee(test::shippedModel(), drawSubject(test::shippedModel(), 13), tmpl, 13);
  for (int n = 0; n < 3; ++n) trainee.learn(standIn(trainee), true);
  const PlanWeights fast = trainee.fastState();
  const PlanWeights slow = trainee.slowState();
  ASSERT_GT(fast.norm(), 0.0);
  trainee.restDays(0);
  EXPECT_EQ(trainee.fastState(), fast);
  trainee.restDays(1);
  EXPECT_EQ(trainee.fastState().norm(), 0.0);
  EXPECT_EQ(trainee.slowState(), slow);
  EXPECT_EQ(trainee.trialsLearned(), 3);
}

TEST(SimulatedTrainee, FeltInPlaneGuidanceShiftsThePlanTheWayItPushed) {
  const HapticProfile tmpl = penDownTemplate();
  const SubjectTraits traits = drawSubject(test::shippedModel(), 21);
  SimulatedTrainee trainee(exactModel(), traits, tmpl, 21);
  const Vec3 force(0.3, 0.4, 0.0);  // 0.5 N
  const HapticProfile before = trainee.plan();
  trainee.learn(standIn(trainee, force), false);
  const HapticProfile after = trainee.plan();
  const Vec2 along = force.head<2>().normalized();
  const Vec2 across(-along.y(), along.x());
  double mean_along = 0.0, mean_across = 0.0;
  for (std::size_t i = 0; i < after.size(); ++i) {
    const Vec2 shift = (after[i].p_WT - before[i].p_WT).head<2>();
    ASSERT_GT(shift.dot(along), 0.0) << "at sample " << i;
    mean_along += shift.dot(along) / static_cast<double>(after.size());
    mean_across += shift.dot(across) / static_cast<double>(after.size());
  }
  // A felt force f stands for a plan error f / K; both states take their share of it.
  const double expected = (traits.fast_rate + traits.slow_rate) * 0.5 / traits.felt_force_stiffness_N_per_m;
  EXPECT_NEAR(mean_along, expected, 0.05 * expected) << "Weber noise averages out over the basis";
  EXPECT_LT(std::abs(mean_across), 0.05 * expected);
  EXPECT_NEAR(-after[500].f_user_W.z(), -before[500].f_user_W.z(), 1e-12) << "the force plan is untouched";
}

TEST(SimulatedTrainee, FeltPushIntoThePaperRaisesThePlannedForce) {
  const HapticProfile tmpl = penDownTemplate();
  const SubjectTraits traits = drawSubject(test::shippedModel(), 22);
  SimulatedTrainee trainee(exactModel(), traits, tmpl, 22);
  const HapticProfile before = trainee.plan();
  trainee.learn(standIn(trainee, Vec3(0.0, 0.0, -0.3)), false);  // the device pushed the pen down 0.3 N
  const HapticProfile after = trainee.plan();
  double mean_rise_N = 0.0, moved = 0.0;
  for (std::size_t i = 0; i < after.size(); ++i) {
    mean_rise_N += (before[i].f_user_W.z() - after[i].f_user_W.z()) / static_cast<double>(after.size());
    moved = std::max(moved, (after[i].p_WT - before[i].p_WT).norm());
  }
  // The push stands for 0.3 N more normal force: 0.3 / sin θ more axial force, of which the
  // normal part is 0.3 N again.
  const double expected = (traits.fast_rate + traits.slow_rate) * 0.3;
  EXPECT_NEAR(mean_rise_N, expected, 0.05 * expected);
  EXPECT_LT(moved, 1e-15) << "the path is untouched";
}

TEST(SimulatedTrainee, UnderGuidanceThePlanSettlesWithTheResidualItsRetentionLeaves) {
  HATTR_STARTS_NO_THREAD();
  // Slacking: the guidance holds the pen on the template and the trainee feels the force that
  // takes; with retention below 1 the plan never gets all the way there — it drifts back until
  // the force it feels sustains it, and the device carries the rest. Without forgetting, it does.
  const HapticProfile tmpl = penDownTemplate(0.3);
  const auto settle = [&](const SubjectTraits& traits) {
    SimulatedTrainee trainee(exactModel(), traits, tmpl, 31);
    const double initial = rmsDistance(trainee.plan(), tmpl);
    for (int n = 0; n < 600; ++n) {
      const HapticProfile plan = trainee.plan();
      HapticProfile recorded(plan.metadata(), plan.rawChannels());
      for (std::size_t i = 0; i < plan.size(); ++i) {
        Sample s = tmpl[i];  // the pen is on the template ...
        s.f_guide_W.head<2>() = traits.felt_force_stiffness_N_per_m * (tmpl[i].p_WT - plan[i].p_WT).head<2>();
        recorded.append(s);  // ... held there against the hand's plan
      }
      trainee.learn(recorded, false);
    }
    return rmsDistance(trainee.plan(), tmpl) / initial;
  };
  const SubjectTraits forgetful = quietTraits();
  const double residual = 1.0 / (1.0 + forgetful.fast_rate / (1.0 - forgetful.fast_retention) +
                                 forgetful.slow_rate / (1.0 - forgetful.slow_retention));
  EXPECT_NEAR(settle(forgetful), residual, 0.01 * residual);
  SubjectTraits retentive = forgetful;
  retentive.fast_retention = retentive.slow_retention = 1.0;
  EXPECT_LT(settle(retentive), 1e-6);
}

TEST(SimulatedTrainee, PerceivedForcesVaryByTheWeberFraction) {
  EXPECT_DOUBLE_EQ(perceivedForce(2.0, 0.07, 0.0), 2.0);
  EXPECT_DOUBLE_EQ(perceivedForce(2.0, 0.07, -1.0), 2.0 * 0.93);
  // Through the trainee: a constant felt force, one perceived value per basis weight.
  const HapticProfile tmpl = penDownTemplate(0.2);
  SubjectTraits traits = quietTraits();
  traits.weber_fraction = 0.07;
  const std::uint64_t seed = test::testSeed(101);
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::vector<double> relative;
  for (std::uint64_t k = 0; k < 200; ++k) {
    SimulatedTrainee trainee(exactModel(), traits, tmpl, seed + k);
    trainee.learn(standIn(trainee, Vec3(0.5, 0.0, 0.0)), false);
    const double unperceived = traits.fast_rate * 0.5 / traits.felt_force_stiffness_N_per_m;
    for (Eigen::Index r = 0; r < trainee.fastState().rows(); ++r) {
      relative.push_back(trainee.fastState()(r, kPlanX) / unperceived - 1.0);
    }
  }
  double mean = 0.0, squares = 0.0;
  for (double x : relative) mean += x / static_cast<double>(relative.size());
  for (double x : relative) squares += (x - mean) * (x - mean);
  const double sd = std::sqrt(squares / static_cast<double>(relative.size() - 1));
  EXPECT_NEAR(mean, 0.0, 0.004);
  EXPECT_NEAR(sd, 0.07, 0.004);
}

TEST(SimulatedTrainee, MotorNoiseGrowsInProportionToTheCommand) {
  // Common random numbers: the same trial seed draws the same normal deviates, so doubling the
  // command (the force plan, or the distance the path covers) must double the noise exactly.
  const auto noise = [](const HapticProfile& tmpl, const SubjectTraits& traits, double t) {
    const SimulatedTrainee trainee(exactModel(), traits, tmpl, 4);
    device::ProfileHandScript plan(trainee.plan());
    const auto hand = trainee.handForTrial(17);
    const device::HandCommand noisy = hand->command(t), planned = plan.command(t);
    return std::pair{Vec3(noisy.p_target_W - planned.p_target_W), noisy.press_N - planned.press_N};
  };
  SubjectTraits traits = quietTraits();
  traits.deviation_rms_m = 0.0;
  traits.position_noise_coefficient = 0.05;
  traits.force_noise_coefficient = 0.05;
  SubjectTraits heavier = traits;
  heavier.force_scale = 2.0;
  const HapticProfile tmpl = penDownTemplate();
  const HapticProfile larger = penDownTemplate(1.0, 2.0);
  for (const double t : {0.1, 0.37, 0.5, 0.81}) {
    const auto [dp, dpress] = noise(tmpl, traits, t);
    ASSERT_GT(dp.norm(), 0.0);
    ASSERT_NE(dpress, 0.0);
    EXPECT_NEAR(noise(tmpl, heavier, t).second, 2.0 * dpress, 1e-12) << "twice the force, twice the force noise";
    EXPECT_LT((noise(larger, traits, t).first - 2.0 * dp).norm(), 1e-15) << "twice the path, twice the path noise";
  }
  SubjectTraits silent = traits;
  silent.position_noise_coefficient = silent.force_noise_coefficient = 0.0;
  const auto [dp0, dpress0] = noise(tmpl, silent, 0.5);
  EXPECT_EQ(dp0.norm(), 0.0);
  EXPECT_EQ(dpress0, 0.0);
}

TEST(SimulatedTrainee, RejectsBadInputWithAMessage) {
  const HapticProfile tmpl = penDownTemplate(0.2);
  SubjectTraits bad = quietTraits();
  bad.fast_rate = 1.5;
  EXPECT_THROW(SimulatedTrainee(test::shippedModel(), bad, tmpl, 1), InputError);
  EXPECT_THROW(SimulatedTrainee(test::shippedModel(), quietTraits(), HapticProfile{}, 1), InputError);
  SimulatedTrainee trainee(test::shippedModel(), quietTraits(), tmpl, 1);
  try {
    trainee.learn(HapticProfile{}, true);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected a recorded trial of at least two samples, got 0"), std::string::npos)
        << e.what();
  }
}

/// The loop glyph's expert script and a trial environment on flat paper.
struct PenFixture {
  PenFixture()
      : script(expertScript(loadGlyph(defaultDataDir() / "glyphs" / "loop.json"))),
        environment("sim://pen", flatWorld(), 1000.0),
        reference(std::make_shared<guidance::ReferenceTrajectory>(script, 1000.0)) {}
  static render::WorldConfig flatWorld() {
    render::WorldConfig w;
    w.relief.kind = render::ReliefConfig::Kind::kFlat;
    return w;
  }
  HapticProfile trial(const SimulatedTrainee& trainee, guidance::TrainingMode mode, std::uint64_t trial_seed) {
    const auto hand = trainee.handForTrial(trial_seed);
    session::TrialSetup setup{.reference = reference, .duration_s = script.duration_s() + 0.5};
    setup.guidance.mode = mode;
    return session::runTrial(environment, setup, *hand).profile;
  }
  /// RMS distance in the plane over the samples where `a` has the pen down [m].
  static double penDownRms(const HapticProfile& a, const HapticProfile& b) {
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
      if (!a[i].pen_down) continue;
      sum += (a[i].p_WT.head<2>() - b[i].p_WT.head<2>()).squaredNorm();
      ++n;
    }
    return std::sqrt(sum / static_cast<double>(n));
  }
  HapticProfile script;
  session::TrialEnvironment environment;
  std::shared_ptr<guidance::ReferenceTrajectory> reference;
};

TEST(SimulatedTraineeOnThePen, TheRecordedTrialFollowsThePlanAndSeeingItHelps) {
  HATTR_STARTS_NO_THREAD();
  PenFixture f;
  SubjectTraits traits = populationTraits(test::shippedModel());
  traits.deviation_rms_m = 0.003;
  traits.pace_cv = 0.0;  // compared with the plan sample by sample
  const std::uint64_t seed = test::testSeed(3);
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  SimulatedTrainee trainee(test::shippedModel(), traits, f.script, seed);
  const HapticProfile plan = trainee.plan();
  const HapticProfile recorded = f.trial(trainee, guidance::TrainingMode::kBasic, 1);
  const double from_plan = PenFixture::penDownRms(plan, recorded);
  const double plan_from_template = PenFixture::penDownRms(plan, f.script);
  EXPECT_LT(from_plan, 0.0015) << "the hand's impedance lags a little, and the motor noise adds";
  EXPECT_LT(from_plan, 0.5 * plan_from_template) << "it writes its plan, not the template";
  trainee.learn(recorded, true);
  EXPECT_LT(PenFixture::penDownRms(trainee.plan(), f.script), plan_from_template);
}

TEST(SimulatedTraineeOnThePen, PositionGuidanceFeltWithTheTemplateHiddenPullsThePlanTowardIt) {
  PenFixture f;
  SubjectTraits traits = populationTraits(test::shippedModel());
  traits.deviation_rms_m = 0.003;
  traits.pace_cv = 0.0;  // compared with the template sample by sample
  SimulatedTrainee trainee(test::shippedModel(), traits, f.script, 8);
  const double before = PenFixture::penDownRms(trainee.plan(), f.script);
  const HapticProfile recorded = f.trial(trainee, guidance::TrainingMode::kPositionControl, 1);
  double felt = 0.0;
  for (const Sample& s : recorded.samples()) felt = std::max(felt, s.f_guide_W.norm());
  ASSERT_GT(felt, 0.1);
  trainee.learn(recorded, false);  // nothing seen: only the force felt
  EXPECT_LT(PenFixture::penDownRms(trainee.plan(), f.script), 0.97 * before);
}

// The plan's series combine the basis column by column instead of through Eigen's product,
// which packs the whole basis first: the same sums in the same order, so the same bits. Checked
// on shapes a model can ask for up to the bound and past it, and on a single sample and tiny
// products (where Eigen's product goes another way, and is used), with zeros, negative zeros
// and values over many orders of magnitude. (Combining one row in turn gave other bits.)
// combineBasis is vectorized (Highway, dispatched at run time): every instruction set compiled
// in that this CPU runs must give Eigen's bits, whole blocks of rows and the rows left over.
TEST(SimulatedTraineeSeries, CombiningTheBasisGivesEigensProductBitForBitOnEveryInstructionSet) {
  int checked = 0;
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (const Eigen::Index rows : {1, 2, 3, 7, 33, 64, 1001, 3555}) {
      for (const Eigen::Index functions : {2, 3, 5, 20, 30, 40, 61, 128, 129, 200}) {
        Eigen::MatrixXd phi(rows, functions);
        PlanWeights weights(functions, 3);
        for (Eigen::Index i = 0; i < rows; ++i) {
          for (Eigen::Index k = 0; k < functions; ++k) {
            phi(i, k) = (i + k) % 7 == 0 ? 0.0 : normal(rng) * std::exp(4.0 * normal(rng));
          }
        }
        for (Eigen::Index k = 0; k < functions; ++k) {
          for (Eigen::Index c = 0; c < 3; ++c) weights(k, c) = k % 5 == 0 ? -0.0 : normal(rng) * 1e-3;
        }
        const Eigen::MatrixX3d product = phi * weights;
        const Eigen::MatrixXd all = detail::combineBasis(phi, weights, {0, 1, 2});
        const Eigen::MatrixXd some = detail::combineBasis(phi, weights, {2, 0});
        const Eigen::MatrixXd one = detail::combineBasis(phi, weights, {1});
        ASSERT_EQ(all.rows(), rows);
        ASSERT_EQ(all.cols(), 3);
        ASSERT_EQ(some.cols(), 2);
        ASSERT_EQ(one.cols(), 1);
        const auto same = [&](const Eigen::MatrixXd& combined, Eigen::Index j, Eigen::Index c) {
          EXPECT_EQ(std::memcmp(combined.col(j).data(), product.col(c).data(),
                                sizeof(double) * static_cast<std::size_t>(rows)), 0)
              << hwy::TargetName(target) << ": " << rows << " samples, " << functions << " functions, column " << c;
          ++checked;
        };
        for (Eigen::Index c = 0; c < 3; ++c) same(all, c, c);
        same(some, 0, 2);
        same(some, 1, 0);
        same(one, 0, 1);
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_EQ(checked, static_cast<int>(hwy::SupportedAndGeneratedTargets().size()) * 8 * 10 * 6);
}

}  // namespace
}  // namespace hattr::sim
