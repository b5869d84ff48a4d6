// The learning hypotheses (docs/simulation.md, "Learning hypotheses"): their model files state
// their own parameters and no other's; every hypothesis draws the same subjects; the
// guidance-dependent learner is the position-plan learner until it feels guidance, then learns
// less from what it sees; the force-plan learner writes with a loose grip and a push, takes a
// felt force as force, and pressing harder than its plan expects drags its path.

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/guidance/reference.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "hattr/sim/participant.hpp"
#include "hattr/sim/trainee.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

const TraineeModel& modelOf(LearningHypothesis h) {
  static const TraineeModel models[] = {loadHypothesisModel(LearningHypothesis::kPositionPlan),
                                        loadHypothesisModel(LearningHypothesis::kForcePlan),
                                        loadHypothesisModel(LearningHypothesis::kGuidanceDependent)};
  return models[static_cast<int>(h)];
}

/// A pen-down template: a circle of 10 mm radius in 1 s at 1 kHz, 1 N normal force at 60°.
HapticProfile circleTemplate() {
  HapticProfile p(ProfileMetadata{.subject = "expert", .skill = "circle"}, RawChannels{.tilt = true});
  const double w = 2.0 * std::numbers::pi;
  for (int i = 0; i <= 1000; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    s.p_WT = Vec3(0.01 * std::cos(w * s.t_s), 0.01 * std::sin(w * s.t_s), 0.0);
    s.v_WT = Vec3(-0.01 * w * std::sin(w * s.t_s), 0.01 * w * std::cos(w * s.t_s), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = s.in_contact = true;
    s.tilt_altitude_rad = std::numbers::pi / 3.0;
    p.append(s);
  }
  return p;
}

/// `trainee`'s plan as a recorded trial shifted by `shift_W` in the plane, with a guidance force.
HapticProfile shiftedPlan(const SimulatedTrainee& trainee, const Vec3& shift_W, const Vec3& f_guide_W) {
  const HapticProfile plan = trainee.plan();
  HapticProfile recorded(plan.metadata(), plan.rawChannels());
  for (Sample s : plan.samples()) {
    s.p_WT += shift_W;
    s.f_guide_W = f_guide_W;
    recorded.append(s);
  }
  return recorded;
}

/// Traits without noise, so plans compare exactly.
SubjectTraits quiet(SubjectTraits t) {
  t.position_noise_coefficient = 0.0;
  t.force_noise_coefficient = 0.0;
  t.weber_fraction = 0.0;
  t.pace_cv = 0.0;
  return t;
}

TEST(LearningHypotheses, EachFileStatesItsOwnParametersAndNoOthers) {
  for (const auto h : allHypotheses()) {
    const TraineeModel& m = modelOf(h);
    EXPECT_EQ(m.hypothesis, h) << hypothesisName(h);
    EXPECT_EQ(parseHypothesis(hypothesisName(h), "test"), h);
  }
  EXPECT_EQ(modelOf(LearningHypothesis::kForcePlan).grip_ratio.value, 0.5);
  EXPECT_FALSE(modelOf(LearningHypothesis::kForcePlan).grip_ratio.source.empty());
  EXPECT_EQ(modelOf(LearningHypothesis::kGuidanceDependent).guidance_dependence.value, 0.25);
  EXPECT_EQ(modelOf(LearningHypothesis::kPositionPlan).grip_ratio.value, 1.0) << "neutral when not stated";

  const std::string base = test::readText(hypothesisModelFile(LearningHypothesis::kPositionPlan));
  const std::string force_plan = test::readText(hypothesisModelFile(LearningHypothesis::kForcePlan));
  // A parameter of another hypothesis.
  std::string wrong = base;
  wrong.replace(wrong.find("\"pace_cv\""), 9,
                "\"grip_ratio\": {\"value\": 0.5, \"unit\": \"1\", \"range\": [0.2, 1], \"source\": \"assumption: x\", "
                "\"per_subject\": {\"kind\": \"fixed\"}}, \"pace_cv\"");
  EXPECT_THROW(
      {
        try {
          (void)parseTraineeModel(wrong, "wrong.json");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("unknown parameter \"parameters.grip_ratio\" for the position-plan "
                                               "hypothesis"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      InputError);
  // Its own parameter missing (plan_friction, the file's last).
  std::string missing = force_plan;
  const auto last = missing.find(",\n    \"plan_friction\"");
  ASSERT_NE(last, std::string::npos);
  missing = missing.substr(0, last) + "\n  }\n}\n";
  EXPECT_THROW(
      {
        try {
          (void)parseTraineeModel(missing, "missing.json");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("missing.json: parameters.plan_friction: missing (every parameter of "
                                               "the force-plan hypothesis must be stated)"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      InputError);
  std::string unknown = base;
  unknown.replace(unknown.find("\"position-plan\""), 15, "\"telepathy\"");
  EXPECT_THROW(
      {
        try {
          (void)parseTraineeModel(unknown, "unknown.json");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("unknown.json: key hypothesis: expected one of position-plan, "
                                               "force-plan, guidance-dependent, got \"telepathy\""),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      InputError);
}

TEST(LearningHypotheses, EveryHypothesisDrawsTheSameSubjects) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const SubjectTraits p = drawSubject(modelOf(LearningHypothesis::kPositionPlan), seed);
    for (const auto h : {LearningHypothesis::kForcePlan, LearningHypothesis::kGuidanceDependent}) {
      SubjectTraits t = drawSubject(modelOf(h), seed);
      EXPECT_EQ(t.slow_rate, p.slow_rate);
      EXPECT_EQ(t.deviation_rms_m, p.deviation_rms_m);
      EXPECT_EQ(t.force_scale, p.force_scale);
      EXPECT_EQ(t.pace_cv, p.pace_cv);
      // Only the hypothesis's own traits differ.
      t.grip_ratio = p.grip_ratio;
      t.plan_friction = p.plan_friction;
      t.guidance_dependence = p.guidance_dependence;
      t.guidance_felt_N = p.guidance_felt_N;
      EXPECT_EQ(t, p) << hypothesisName(h) << " seed " << seed;
    }
  }
}

TEST(LearningHypotheses, AGuidanceDependentLearnerLearnsLessFromWhatItSeesOnlyInATrialItWasGuided) {
  const HapticProfile tmpl = circleTemplate();
  const auto make = [&](LearningHypothesis h) {
    return SimulatedTrainee(modelOf(h), quiet(drawSubject(modelOf(h), 5)), tmpl, 5);
  };
  SimulatedTrainee plain = make(LearningHypothesis::kPositionPlan);
  SimulatedTrainee dependent = make(LearningHypothesis::kGuidanceDependent);
  const double d = dependent.traits().guidance_dependence;
  const double felt_N = dependent.traits().guidance_felt_N;
  ASSERT_GT(d, 0.0);
  // Unguided: the same learner to the bit.
  const Vec3 shift(0.002, -0.001, 0.0);
  plain.learn(shiftedPlan(plain, shift, Vec3::Zero()), true);
  dependent.learn(shiftedPlan(dependent, shift, Vec3::Zero()), true);
  EXPECT_EQ(plain.fastState(), dependent.fastState());
  EXPECT_EQ(plain.slowState(), dependent.slowState());
  // Guided, by a push into the paper (felt in the axial channel only): the position-plan
  // learner takes in what it saw in full, the guidance-dependent one (1 − d) of it.
  const Vec3 guide(0.0, 0.0, -2.0 * felt_N);
  const PlanWeights plain_before = plain.fastState();
  const PlanWeights dependent_before = dependent.fastState();
  plain.learn(shiftedPlan(plain, shift, guide), true);
  dependent.learn(shiftedPlan(dependent, shift, guide), true);
  const auto seen = [](const SimulatedTrainee& t, const PlanWeights& before) {
    return (t.fastState().leftCols<2>() - t.traits().fast_retention * before.leftCols<2>()).norm();
  };
  ASSERT_GT(seen(plain, plain_before), 0.0);
  EXPECT_NEAR(seen(dependent, dependent_before) / seen(plain, plain_before), 1.0 - d, 1e-9);
  EXPECT_EQ(dependent.fastState().col(kPlanAxialForce), plain.fastState().col(kPlanAxialForce))
      << "what it felt it learns as the position-plan learner does";
  // Guidance below what it notices is not leaned on.
  SimulatedTrainee faint = make(LearningHypothesis::kGuidanceDependent);
  SimulatedTrainee faint_plain = make(LearningHypothesis::kPositionPlan);
  faint.learn(shiftedPlan(faint, shift, Vec3(0.0, 0.0, -0.5 * felt_N)), true);
  faint_plain.learn(shiftedPlan(faint_plain, shift, Vec3(0.0, 0.0, -0.5 * felt_N)), true);
  EXPECT_EQ(faint.fastState(), faint_plain.fastState());
}

TEST(LearningHypotheses, AForcePlanLearnerTakesAFeltForceAsForceToPushWith) {
  const HapticProfile tmpl = circleTemplate();
  const auto& model = modelOf(LearningHypothesis::kForcePlan);
  SubjectTraits traits = quiet(drawSubject(model, 7));
  traits.deviation_rms_m = 0.0;
  SimulatedTrainee trainee(model, traits, tmpl, 7);
  const HapticProfile before = trainee.plan();
  // Its plan aims at the template's path and pushes along the motion with the friction it
  // expects at the template's normal force.
  const Vec3 tangent = tmpl[250].v_WT.normalized();
  EXPECT_NEAR((before[250].p_WT - tmpl[250].p_WT).norm(), 0.0, 1e-15);
  EXPECT_NEAR(before[250].f_user_W.head<2>().dot(tangent.head<2>()), traits.plan_friction * 1.0, 1e-9);
  // A felt in-plane force: its push grows by the states' share of it, in newtons.
  const Vec3 felt(0.3, 0.0, 0.0);
  trainee.learn(shiftedPlan(trainee, Vec3::Zero(), felt), false);
  const HapticProfile after = trainee.plan();
  double mean_rise_N = 0.0;
  for (std::size_t i = 0; i < after.size(); ++i) {
    mean_rise_N += (after[i].f_user_W.x() - before[i].f_user_W.x()) / static_cast<double>(after.size());
    ASSERT_EQ(after[i].p_WT, before[i].p_WT) << "the path it aims at stays the template's";
  }
  const double expected = (traits.fast_rate + traits.slow_rate) * 0.3;
  EXPECT_NEAR(mean_rise_N, expected, 0.05 * expected);
  // Its hand writes with the grip's share of the impedance and the push.
  const auto hand = trainee.handForTrial(1);
  const device::HandCommand cmd = hand->command(0.25);
  EXPECT_EQ(cmd.grip, traits.grip_ratio);
  EXPECT_GT(cmd.push_W.head<2>().dot(tangent.head<2>()), 0.0);
  // A position-plan learner's hand grips fully and does not push.
  const auto& plain_model = modelOf(LearningHypothesis::kPositionPlan);
  const SimulatedTrainee plain(plain_model, quiet(drawSubject(plain_model, 7)), tmpl, 7);
  const device::HandCommand plain_cmd = plain.handForTrial(1)->command(0.25);
  EXPECT_EQ(plain_cmd.grip, 1.0);
  EXPECT_EQ(plain_cmd.push_W, Vec3::Zero());
}

TEST(LearningHypotheses, OnThePenAForcePlanWriterWhoPressesHarderThanItsPlanExpectsLagsMore) {
  HATTR_STARTS_NO_THREAD();
  // The paper's section 4.3: the path follows from the force; pressing harder than the force
  // plan expects adds friction it does not push against, so the pen falls behind.
  const HapticProfile script = expertScript(loadGlyph(defaultDataDir() / "glyphs" / "loop.json"));
  render::WorldConfig world;
  world.relief.kind = render::ReliefConfig::Kind::kFlat;
  session::TrialEnvironment env("sim://pen", world, 1000.0);
  const auto lagOf = [&](LearningHypothesis h, double force_scale) {
    SubjectTraits traits = quiet(populationTraits(modelOf(h)));
    traits.deviation_rms_m = 0.0;
    traits.force_scale = force_scale;
    const SimulatedTrainee trainee(modelOf(h), traits, script, 3);
    const auto hand = trainee.handForTrial(1);
    const HapticProfile rec =
        session::runTrial(env, {.duration_s = script.duration_s() + 0.5}, *hand).profile;
    // Mean distance behind the script along its motion, over the pen-down samples.
    double behind = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < std::min(rec.size(), script.size()); ++i) {
      const Sample& s = script[i];
      if (!s.pen_down || s.v_WT.head<2>().norm() < 0.01) continue;
      behind += (s.p_WT - rec[i].p_WT).head<2>().dot(s.v_WT.head<2>().normalized());
      ++n;
    }
    return behind / n;
  };
  const double force_light = lagOf(LearningHypothesis::kForcePlan, 1.0);
  const double force_heavy = lagOf(LearningHypothesis::kForcePlan, 1.5);
  const double position_light = lagOf(LearningHypothesis::kPositionPlan, 1.0);
  const double position_heavy = lagOf(LearningHypothesis::kPositionPlan, 1.5);
  EXPECT_GT(force_heavy, force_light);
  EXPECT_GT(position_heavy, position_light) << "friction drags any pen";
  // With half the grip, the extra friction drags the force-plan writer about twice as far.
  EXPECT_GT(force_heavy - force_light, 1.5 * (position_heavy - position_light))
      << "force plan " << force_light << " → " << force_heavy << " m, position plan " << position_light << " → "
      << position_heavy << " m";
}

TEST(LearningHypotheses, TheHandWritesWithTheGripsShareOfItsImpedanceAndItsPush) {
  const device::HandImpedance hand{.stiffness_N_per_m = 300.0, .damping_N_s_per_m = 4.0};
  device::HandCommand cmd;
  cmd.p_target_W = Vec3(0.01, 0.0, 0.0);
  cmd.v_target_W = Vec3(0.0, 0.1, 0.0);
  cmd.press_N = 1.0;
  cmd.pen_down = true;
  const Vec3 full = device::handForce(hand, cmd, Vec3::Zero(), Vec3::Zero());
  cmd.grip = 0.5;
  cmd.push_W = Vec3(0.2, -0.1, 5.0);
  const Vec3 loose = device::handForce(hand, cmd, Vec3::Zero(), Vec3::Zero());
  EXPECT_NEAR(loose.x(), 0.5 * full.x() + 0.2, 1e-12);
  EXPECT_NEAR(loose.y(), 0.5 * full.y() - 0.1, 1e-12);
  EXPECT_EQ(loose.z(), full.z()) << "the press is the press: neither grip nor push reaches it";
  try {
    (void)device::ProfileHandScript(circleTemplate(), 1.0, Vec3::Zero(), {.grip = 0.0});
    ADD_FAILURE() << "a grip of 0 was accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "hand script: grip: expected a share in (0, 1], got 0");
  }
}

TEST(LearningHypotheses, AStudyOptionPicksTheHypothesisAndAForcePlanTraineeNeedsTheSimulatedPen) {
  session::SubjectRecord subject{.id = "S01", .spec = {.id = "S01", .participant = "simulated", .seed = 1}};
  subject.spec.options = {{"hypothesis", "force-plan"}};
  EXPECT_EQ(subjectTraineeModel(subject).hypothesis, LearningHypothesis::kForcePlan);
  EXPECT_NE(makeUnattendedParticipant(subject, circleTemplate(), "sim://pen"), nullptr);
  const auto refusal = [&](const std::string& device) {
    try {
      (void)makeUnattendedParticipant(subject, circleTemplate(), device);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(refusal("plugin:sim"), "subject S01 is a force-plan trainee, whose grip and push only the simulated pen "
                                   "renders: expected a sim:// device, got \"plugin:sim\"");
  subject.spec.options = {{"hypothesis", "guidance-dependent"}};
  EXPECT_NE(makeUnattendedParticipant(subject, circleTemplate(), "plugin:sim"), nullptr) << "its hand is an ordinary one";
  subject.spec.options = {{"hypothesis", 3}};
  EXPECT_EQ(refusal("sim://pen"), "subject S01: option hypothesis: expected a string, got 3");
  subject.spec.options = {{"hypothesis", "force-plan"}, {"model", "x.json"}};
  EXPECT_EQ(refusal("sim://pen"), "subject S01: options model and hypothesis: expected one of them (a model file "
                                  "states its hypothesis), got both");
}

}  // namespace
}  // namespace hattr::sim
