// The studio's view-models without widgets: mapping the mouse to the paper, the mouse hand,
// trails and series, playback, profile files, scoring, the relief image.
#include <QtTest>
#include <cmath>
#include <fstream>
#include <numbers>

#include "core/mouse_hand.hpp"
#include "core/paper_mapping.hpp"
#include "core/profile_files.hpp"
#include "core/relief_image.hpp"
#include "core/scene_camera.hpp"
#include "core/series.hpp"
#include "core/window_fit.hpp"
#include "core/trial_scoring.hpp"
#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/core/error.hpp"
#include "hattr/device/simulated_device.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "studio_test_support.hpp"

using namespace hattr;
using namespace hattr::studio;

class StudioCoreTest : public QObject {
  Q_OBJECT

 private slots:
  // ---- PaperMapping ----
  void mappingRoundTripsBetweenPixelsAndMetres() {
    PaperMapping m;
    m.setPaperRect(-0.08, -0.06, 0.08, 0.06);
    m.setWidgetSize(820, 620, 10);
    for (const auto& p : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(-0.08, 0.06), Eigen::Vector2d(0.0312, -0.0177)}) {
      const Eigen::Vector2d back = m.toPaper(m.toWidget(p.x(), p.y()));
      QVERIFY((back - p).norm() < 1e-12);
    }
  }
  void mappingKeepsOneScaleAndCentresThePaper() {
    PaperMapping m;
    m.setPaperRect(-0.08, -0.06, 0.08, 0.06);  // 4:3
    m.setWidgetSize(1000, 500, 0);             // wider than the paper: height decides
    QCOMPARE(m.pixelsPerMetre(), 500.0 / 0.12);
    const QRectF r = m.paperRectPx();
    QVERIFY(std::abs(r.center().x() - 500.0) < 1e-9);
    QVERIFY(std::abs(r.height() - 500.0) < 1e-9);
    QVERIFY(std::abs(r.width() - 500.0 * 4.0 / 3.0) < 1e-9);
  }
  void mappingPutsPaperYUpOnTheScreen() {
    PaperMapping m;
    m.setPaperRect(-0.08, -0.06, 0.08, 0.06);
    m.setWidgetSize(800, 600, 0);
    // Away from the writer (+y) is up (smaller pixel y); right (+x) is right.
    QVERIFY(m.toWidget(0.0, 0.01).y() < m.toWidget(0.0, 0.0).y());
    QVERIFY(m.toWidget(0.01, 0.0).x() > m.toWidget(0.0, 0.0).x());
    // The paper's top-left corner is (x_min, y_max).
    const QPointF corner = m.toWidget(-0.08, 0.06);
    QVERIFY(std::abs(corner.x() - m.paperRectPx().left()) < 1e-9);
    QVERIFY(std::abs(corner.y() - m.paperRectPx().top()) < 1e-9);
  }
  void mappingClampsAPointOffThePaper() {
    PaperMapping m;
    m.setPaperRect(-0.08, -0.06, 0.08, 0.06);
    m.setWidgetSize(800, 600, 20);
    const Eigen::Vector2d p = m.clampToPaper(m.toPaper(QPointF(-50.0, 10000.0)));
    QCOMPARE(p.x(), -0.08);
    QCOMPARE(p.y(), -0.06);
  }
  void mappingRefusesAnEmptyRectangleSayingWhatItGot() {
    PaperMapping m;
    try {
      m.setPaperRect(0.1, 0.0, 0.1, 0.05);
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY(QString(e.what()).contains("x_min < x_max"));
      QVERIFY(QString(e.what()).contains("0.1"));
    }
  }

  // ---- PressScale and the mouse hand ----
  void wheelNotchesStepThePressForceWithinItsRange() {
    QCOMPARE(PressScale::afterWheel(1.2, 120), 1.3);
    QVERIFY(std::abs(PressScale::afterWheel(1.2, -240) - 1.0) < 1e-12);
    QCOMPARE(PressScale::afterWheel(2.95, 600), PressScale::kMax_N);
    QCOMPARE(PressScale::afterWheel(0.05, -600), PressScale::kMin_N);
    QCOMPARE(PressScale::toSliderSteps(1.2), 12);
    QVERIFY(std::abs(PressScale::fromSliderSteps(12) - 1.2) < 1e-12);
    QCOMPARE(PressScale::toSliderSteps(PressScale::fromSliderSteps(17)), 17);
  }
  void mouseHandStartsAtTheCursorAtRest() {
    MouseHand hand;
    hand.setInput({.x_m = 0.01, .y_m = -0.02, .pen_down = false, .press_N = 1.0});
    const device::HandCommand c = hand.command(0.0);
    QCOMPARE(c.p_target_W.x(), 0.01);
    QCOMPARE(c.p_target_W.y(), -0.02);
    QCOMPARE(c.p_target_W.z(), hand.params().lift_height_m);
    QCOMPARE(c.v_target_W.norm(), 0.0);
    QVERIFY(!c.pen_down);
    QCOMPARE(c.press_N, 0.0);
  }
  void mouseHandFollowsAJumpOfTheCursorSmoothlyWithoutOvershoot() {
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0});
    (void)hand.command(0.0);
    hand.setInput({.x_m = 0.01, .y_m = 0.0});
    double previous = 0.0;
    double max_step = 0.0;
    for (int i = 1; i <= 500; ++i) {
      const double x = hand.command(i * 1e-3).p_target_W.x();
      QVERIFY(x >= previous - 1e-15);  // monotonic: critically damped
      QVERIFY(x <= 0.01 + 1e-12);      // no overshoot
      max_step = std::max(max_step, x - previous);
      previous = x;
    }
    QVERIFY(std::abs(previous - 0.01) < 1e-5);  // there after 0.5 s
    QVERIFY(max_step < 0.001);                  // never a jump of the whole 10 mm
  }
  void mouseHandPutsThePenDownAndPressesWithALag() {
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.5});
    (void)hand.command(0.0);
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = true, .press_N = 1.5});
    const device::HandCommand first = hand.command(0.001);
    QVERIFY(first.pen_down);
    QVERIFY(first.press_N > 0.0 && first.press_N < 0.2);
    device::HandCommand later;
    for (int i = 2; i <= 300; ++i) later = hand.command(i * 1e-3);
    QVERIFY(std::abs(later.press_N - 1.5) < 1e-3);
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.5});
    device::HandCommand up;
    for (int i = 301; i <= 600; ++i) up = hand.command(i * 1e-3);
    QVERIFY(!up.pen_down);
    QVERIFY(up.press_N < 1e-3);
  }
  void mouseHandRewindRestartsAtTheCurrentCursor() {
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0});
    for (int i = 0; i < 10; ++i) (void)hand.command(i * 1e-3);
    hand.setInput({.x_m = 0.03, .y_m = 0.02});
    hand.rewind();
    const device::HandCommand c = hand.command(5.0);
    QCOMPARE(c.p_target_W.x(), 0.03);
    QCOMPARE(c.p_target_W.y(), 0.02);
  }
  void mouseHandWritesOnThePaperThroughTheServoLoop() {
    // The whole chain: mouse hand → simulated pen → paper → safety → loop, simulated time.
    MouseHand hand;
    hand.setInput({.x_m = 0.01, .y_m = 0.005, .pen_down = false, .press_N = 1.2});
    device::SimulatedPenParams params;
    params.start_position_W = Vec3(0.01, 0.005, 0.003);
    device::SimulatedDevice pen(params, &hand);
    render::PaperRenderer paper(render::PaperParams{});
    servo::ServoLoop loop(pen, servo::ServoConfig{});
    loop.setWorld(&paper);
    loop.runSimulated(400);  // forces ramp in, pen held up
    Sample s;
    (void)loop.latest().read(s);
    QVERIFY(!s.in_contact);
    hand.setInput({.x_m = 0.02, .y_m = 0.005, .pen_down = true, .press_N = 1.2});
    loop.runSimulated(600);
    (void)loop.latest().read(s);
    QVERIFY(s.in_contact);
    QVERIFY(s.f_user_W.z() < -0.5);                // pressing on the paper
    QVERIFY(std::abs(s.p_WT.x() - 0.02) < 0.003);  // at the cursor, within friction's pull
    QVERIFY(std::abs(s.p_WT.y() - 0.005) < 0.002);
  }

  // ---- Trails, series, playback ----
  void trailSplitsStrokesWherePenLifts() {
    Trail trail;
    Sample s;
    for (int i = 0; i < 10; ++i) {
      s.pen_down = i < 3 || i >= 6;
      s.p_WT = Vec3(i * 1e-3, 0.0, 0.0);
      trail.append(s);
    }
    QCOMPARE(trail.strokes().size(), std::size_t{2});
    QCOMPARE(trail.strokes()[0].size(), std::size_t{3});
    QCOMPARE(trail.strokes()[1].size(), std::size_t{4});
    QCOMPARE(trail.pointCount(), std::size_t{7});
  }
  void trailForgetsTheOldestStrokesBeyondItsLimit() {
    Trail trail(5);
    Sample s;
    for (int i = 0; i < 12; ++i) {
      s.pen_down = i % 4 != 3;  // strokes of 3
      trail.append(s);
    }
    QVERIFY(trail.pointCount() <= 5);
    QVERIFY(!trail.empty());
  }
  void forceSeriesFromAProfileKeepsItsSpanAndLimit() {
    const HapticProfile p = test::figureEightScript(1.0);
    const ForceSeries series = ForceSeries::fromProfile(p, 50);
    QVERIFY(series.size() <= 51);
    QCOMPARE(series.t_s.front(), 0.0);
    QCOMPARE(series.t_s.back(), p.samples().back().t_s);
    const auto [lo, hi] = series.forceRange();
    QCOMPARE(lo, -0.8);
    QCOMPARE(hi, 0.0);
  }
  void playbackAdvancesWithTheClockAndStopsAtTheEnd() {
    const HapticProfile p = test::figureEightScript(1.0);
    Playback playback;
    playback.load(&p);
    playback.play(100.0);
    QCOMPARE(playback.time_s(100.5), 0.5);
    QCOMPARE(playback.indexAt(0.5), std::size_t{100});  // 200 Hz
    QCOMPARE(playback.indexAt(0.5024), std::size_t{100});
    QVERIFY(!playback.finished(100.9));
    QVERIFY(playback.finished(101.0));
    QCOMPARE(playback.time_s(105.0), 1.0);
    playback.pause(100.25);
    QCOMPARE(playback.time_s(200.0), 0.25);
    playback.setSpeed(2.0);
    playback.play(300.0);
    QCOMPARE(playback.time_s(300.25), 0.75);
  }

  // ---- Profile files ----
  void savingRefusesToReplaceAFileUnlessConfirmed() {
    const auto dir = test::freshTempDir("save");
    const auto file = dir / "take.csv";
    const HapticProfile p = test::figureEightScript(0.5);
    QCOMPARE(saveProfile(p, file, false), SaveOutcome::kSaved);
    const auto size_before = std::filesystem::file_size(file);
    HapticProfile other = test::figureEightScript(0.8);
    QCOMPARE(saveProfile(other, file, false), SaveOutcome::kNeedsConfirmation);
    QCOMPARE(std::filesystem::file_size(file), size_before);  // untouched
    QCOMPARE(saveProfile(other, file, true), SaveOutcome::kSaved);
    QCOMPARE(io::readProfileCsv(file).size(), other.size());
    std::filesystem::remove_all(dir);
  }
  void savingIntoAMissingFolderSaysWhere() {
    const HapticProfile p = test::figureEightScript(0.5);
    try {
      (void)saveProfile(p, "/nonexistent-hattr-folder/take.csv", false);
      QFAIL("no error");
    } catch (const Error& e) {
      QVERIFY2(QString(e.what()).contains("nonexistent-hattr-folder"), e.what());
    }
  }
  void namingATakeChecksTheFieldsAndTrimsThem() {
    const HapticProfile p = test::figureEightScript(0.5);
    const HapticProfile named = nameTake(p, "  Ana ", "na ");
    QCOMPARE(named.metadata().subject, std::string("Ana"));
    QCOMPARE(named.metadata().skill, std::string("na"));
    try {
      (void)nameTake(p, "  ", "na");
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("expert name: expected a non-empty text"), e.what());
    }
    try {
      (void)nameTake(p, "Ana", "n\na");
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("character: expected one line"), e.what());
    }
    QCOMPARE(suggestedTakeFileName("Ana María", "ந/1"), std::string("expert_Ana_María_ந_1.csv"));
  }
  void loadingABadReferenceNamesTheFile() {
    const auto dir = test::freshTempDir("ref");
    const auto file = dir / "bad.csv";
    std::ofstream(file) << "this is not a profile\n";
    try {
      (void)loadReferenceProfile(file.string());
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("bad.csv"), e.what());
    }
    // A profile with nothing written is no reference.
    HapticProfile lifted = test::figureEightScript(0.5);
    HapticProfile up(lifted.metadata());
    for (Sample s : lifted.samples()) {
      s.pen_down = false;
      up.append(s);
    }
    io::writeProfileCsv(up, dir / "up.csv");
    try {
      (void)loadReferenceProfile((dir / "up.csv").string());
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("pen down"), e.what());
    }
    std::filesystem::remove_all(dir);
  }

  // ---- Scoring ----
  void scoringATrialAgainstItselfGivesZero() {
    const HapticProfile p = test::figureEightScript(1.0);
    const analysis::TrialScore s = scoreTrial(p, p);
    QCOMPARE(s.shape(), 0.0);
    QCOMPARE(s.force(), 0.0);
    QCOMPARE(s.z, 0.0);
  }
  void scoringIsWhatHattrDtwComputes() {
    const HapticProfile expert = test::figureEightScript(1.0, 0.8);
    const HapticProfile trial = test::figureEightScript(1.3, 1.1, Vec3(0.004, -0.002, 0.0));
    const analysis::TrialScore s = scoreTrial(expert, trial);
    // The CLI's computation (apps/hattr/cmd_analysis.cpp runDtw), channel by channel.
    const auto cli = [&](const char* name) {
      const auto a = analysis::normalize(expert.channel(name), analysis::Normalization::kPaper);
      const auto b = analysis::preprocessTrial(trial.channel(Channel::kTime), trial.channel(name),
                                               expert.channel(Channel::kTime), analysis::Normalization::kPaper);
      return analysis::dtw(a, b).cost;
    };
    QCOMPARE(s.x, cli("x"));
    QCOMPARE(s.y, cli("y"));
    QCOMPARE(s.fz, cli("fz"));
    QCOMPARE(s.shape(), s.x + s.y);
    QCOMPARE(s.force(), s.fx + s.fy + s.fz);
  }
  void scoringADifferentShapeCostsMore() {
    const HapticProfile expert = test::figureEightScript(1.0);
    HapticProfile circle(expert.metadata());
    for (Sample s : expert.samples()) {
      s.p_WT = Vec3(0.02 * std::cos(6.283185307179586 * s.t_s), 0.02 * std::sin(6.283185307179586 * s.t_s), 0.0);
      circle.append(s);
    }
    const HapticProfile similar = test::figureEightScript(1.1, 0.8, Vec3(0.001, 0.0, 0.0));
    QVERIFY(scoreTrial(expert, circle).shape() > 2.0 * scoreTrial(expert, similar).shape());
  }
  void scoringRefusesATooShortTrialSayingWhich() {
    const HapticProfile expert = test::figureEightScript(1.0);
    HapticProfile one(expert.metadata());
    one.append(expert[0]);
    try {
      (void)scoreTrial(expert, one);
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("the trial has 1 samples in its writing span"), e.what());
    }
  }

  // ---- Relief image ----
  void reliefImageShowsTheGrainAndFlatPaperIsPlain() {
    const auto grain = render::HeightField::paperGrain(0.16, 128, 1e-5, 5e-4, 2);
    const QImage image = reliefImage(grain, -0.08, -0.06, 0.08, 0.06, 160, 120);
    QCOMPARE(image.size(), QSize(160, 120));
    int lo = 255, hi = 0;
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        lo = std::min(lo, qGray(image.pixel(x, y)));
        hi = std::max(hi, qGray(image.pixel(x, y)));
      }
    }
    QVERIFY(hi - lo > 30);  // visible grain
    QVERIFY(lo > 150);      // still light paper
    const QImage flat = reliefImage(render::HeightField{}, -0.08, -0.06, 0.08, 0.06, 16, 12);
    QCOMPARE(flat.pixelColor(3, 4), paperColour());
  }

  // ---- The 3-D view's geometry ----
  void theBarrelPointsAlongTheTiltFromTheTip() {
    const Vec3 tip(0.01, -0.02, 0.003);
    constexpr double kL = 0.04, kDeg = std::numbers::pi / 180.0;
    // Upright: straight above the tip.
    QVERIFY((penTop_W(tip, 1.234, 90.0 * kDeg, kL) - (tip + Vec3(0.0, 0.0, kL))).norm() < 1e-12);
    // Lying flat at azimuth 0: along +y; at 90°: clockwise from +y seen from above, +x.
    QVERIFY((penTop_W(tip, 0.0, 0.0, kL) - (tip + Vec3(0.0, kL, 0.0))).norm() < 1e-12);
    QVERIFY((penTop_W(tip, 90.0 * kDeg, 0.0, kL) - (tip + Vec3(kL, 0.0, 0.0))).norm() < 1e-12);
    // 30° above the paper toward -y (azimuth 180°): cos 30° along the paper, sin 30° up.
    const Vec3 d = penTop_W(tip, 180.0 * kDeg, 30.0 * kDeg, kL) - tip;
    QVERIFY((d - Vec3(0.0, -kL * std::cos(30.0 * kDeg), kL * std::sin(30.0 * kDeg))).norm() < 1e-12);
  }
  void theCameraFitsThePaperAndShowsHeightAsUp() {
    SceneCamera camera;
    const Vec3 lo(-0.08, -0.06, 0.0), hi(0.08, 0.06, 0.04);
    camera.frame(lo, hi, -20.0 * std::numbers::pi / 180.0, 35.0 * std::numbers::pi / 180.0, 400, 300, 10.0);
    // Every corner of the box in the viewport, and the box touching its margins on one axis.
    double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector2d p = camera.toPixels(Vec3((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                                                     (corner & 4) ? hi.z() : lo.z()));
      min_x = std::min(min_x, p.x());
      max_x = std::max(max_x, p.x());
      min_y = std::min(min_y, p.y());
      max_y = std::max(max_y, p.y());
    }
    QVERIFY(min_x >= 10.0 - 1e-9 && max_x <= 390.0 + 1e-9 && min_y >= 10.0 - 1e-9 && max_y <= 290.0 + 1e-9);
    QVERIFY(std::abs(min_x - 10.0) < 1e-9 || std::abs(min_y - 10.0) < 1e-9);
    // Higher is up on the screen; the paper's far edge (+y) is above its near edge; +x is right.
    QVERIFY(camera.toPixels(Vec3(0, 0, 0.01)).y() < camera.toPixels(Vec3(0, 0, 0)).y());
    QVERIFY(camera.toPixels(Vec3(0, 0.05, 0)).y() < camera.toPixels(Vec3(0, -0.05, 0)).y());
    QVERIFY(camera.toPixels(Vec3(0.05, 0, 0)).x() > camera.toPixels(Vec3(-0.05, 0, 0)).x());
    // The far edge is deeper than the near one.
    QVERIFY(camera.depth(Vec3(0, 0.05, 0)) > camera.depth(Vec3(0, -0.05, 0)));
  }
  // The first window on a screen: 1280 x 820 where it fits; on a 1280 x 800 screen with a
  // panel, or a 1024 x 680 one, within it less the frame (so the status bar shows), never
  // below the window's smallest size.
  void theFirstWindowFitsTheScreenWithItsFrame() {
    const QSize frame(8, 40), minimum(853, 600);
    QCOMPARE(fitWindow(kPreferredWindowSize, QSize(1920, 1050), frame, minimum), QSize(1280, 820));
    QCOMPARE(fitWindow(kPreferredWindowSize, QSize(1280, 768), frame, minimum), QSize(1272, 728));
    QCOMPARE(fitWindow(kPreferredWindowSize, QSize(1024, 680), QSize(0, 0), minimum), QSize(1024, 680));
    QCOMPARE(fitWindow(kPreferredWindowSize, QSize(800, 500), frame, minimum), minimum);
  }

  void aMicrometreReliefIsRaisedAndFlatPaperIsNot() {
    QCOMPARE(reliefExaggeration(render::HeightField{}, 0.16), 1.0);
    // Heights from 0 to 20 µm on a 0.16 m paper: raised to 3 % of it (4.8 mm), 240 times.
    const auto ramp = render::HeightField::fromFunction(5, 5, Vec3(-0.08, -0.08, 0.0), 0.04,
                                                        [](double x, double) { return (x + 0.08) / 0.16 * 2e-5; });
    QVERIFY(std::abs(reliefExaggeration(ramp, 0.16) - 240.0) < 1e-9);
    // A relief already higher than that is never lowered.
    const auto tall = render::HeightField::fromFunction(5, 5, Vec3(-0.08, -0.08, 0.0), 0.04,
                                                        [](double x, double) { return (x + 0.08) / 0.16 * 0.01; });
    QCOMPARE(reliefExaggeration(tall, 0.16), 1.0);
  }
};

QTEST_GUILESS_MAIN(StudioCoreTest)
#include "studio_core_test.moc"
