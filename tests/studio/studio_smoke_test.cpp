// The studio end to end, offscreen: the main window on the real servo loop in real time, the
// mouse driven along a path like a person's hand. A training trial is run and scored, the
// window is saved as a screenshot (studio_smoke.png in the build folder) and its pixels are
// checked for the paper's grain, the expert's reference and the pen's trail. Then a take is
// recorded and saved, a study trial is run and stored, and the study is reviewed.
#include <QComboBox>
#include <QPushButton>
#include <QLabel>
#include <QStatusBar>
#include <QTabWidget>
#include <QtTest>
#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "screen_checks.hpp"
#include "studio_test_support.hpp"
#include "core/series.hpp"
#include "core/study_session.hpp"
#include "ui/learning_curve.hpp"
#include "ui/main_window.hpp"
#include "ui/paper_view.hpp"
#include "ui/pen_scene_view.hpp"
#include "ui/profile_plot.hpp"
#include "ui/record_tab.hpp"
#include "ui/train_tab.hpp"

using namespace hattr;
using namespace hattr::studio;

// Screenshots are kept in the working folder: ctest runs the test in its build folder.
#define HATTR_STUDIO_SCREENSHOT_DIR "."

using test::sendMouse;
using test::shareDrawn;

class StudioSmokeTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    dir_ = test::freshTempDir("smoke");
    // The expert: a figure-eight recorded through runTrial, saved as a haptic profile.
    session::TrialEnvironment flat("sim://pen", test::flatWorld(), 1000.0);
    expert_ = test::recordExpert(flat);
    expert_file_ = dir_ / "expert.csv";
    io::writeProfileCsv(expert_, expert_file_);

    auto settings =
        std::make_unique<QSettings>(QString::fromStdString((dir_ / "studio.ini").string()), QSettings::IniFormat);
    settings->setValue("train/settle_s", 0.5);
    settings->setValue("record/trigger", 1);  // start/stop buttons
    settings->setValue("record/name", "Ana");
    // The mouse presses 0.8 N, not the default 1.2 N: a take recorded in real time overshoots at
    // touch-down, more on a loaded host (1.80 N was seen beside the doc tests), and a take used
    // as the reference must stay within the pen's 1.75 N whatever the load.
    settings->setValue("input/press_N", 0.8);
    settings->setValue("record/character", "eight");
    settings->setValue("view/engineer", true);  // it reads the loop's counters and the technical names
    window_ = std::make_unique<MainWindow>(std::move(settings));
    window_->setInteractive(false);
    window_->resize(1280, 820);
    window_->show();
    QVERIFY(QTest::qWaitForWindowExposed(window_.get()));
  }

  void cleanupTestCase() {
    window_.reset();
    std::filesystem::remove_all(dir_);
  }

  void aTrainingTrialIsDrawnScoredAndScreenshot() {
    MainWindow& w = *window_;
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));
    // A bad file: refused with a message naming it, nothing else changes.
    QVERIFY(!w.loadReference(QString::fromStdString((dir_ / "missing.csv").string())));
    QVERIFY2(w.lastError().contains("missing.csv"), qPrintable(w.lastError()));
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));
    w.tabs()->setCurrentIndex(MainWindow::kTabTrain);
    w.setMode(guidance::TrainingMode::kPositionControl);
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    QCOMPARE(w.activity(), MainWindow::Activity::kTrial);

    // A training trial ends when the person is done: 1 s after the pen is lifted, at most at
    // three times the expert's duration.
    QCOMPARE(w.rig().spec().pen_up_end_s, 1.0);
    QVERIFY(w.rig().spec().duration_s > 3.0 * expert_.duration_s() - 1e-9);

    // A person 8 mm to the right of the expert, at the expert's pace, who lifts the pen at the end.
    const double max_s = w.rig().spec().duration_s;
    double ran_s = 0.0;
    driveAlongExpert(w, Vec3(0.008, 0.0, 0.0), MainWindow::Activity::kTrial,
                     HATTR_STUDIO_SCREENSHOT_DIR "/studio_trial.png", &ran_s);
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    // The window ended the trial when the rig said the writing was over, not at the maximum.
    QVERIFY2(ran_s < max_s - 0.5, qPrintable(QString("ran %1 s of a %2 s maximum").arg(ran_s).arg(max_s)));
    QVERIFY2(w.lastTrial().has_value(), qPrintable(w.lastError()));
    QVERIFY(w.lastTrial()->size() > 1000);
    QVERIFY(w.lastTrial()->penDownCount() > 500);
    QVERIFY(w.lastScores().has_value());
    QVERIFY(w.lastScores()->shape() > 0.0);
    // The learning curve has the trial: its mode, its scores.
    QCOMPARE(w.learningCurve()->points().size(), std::size_t{1});
    QCOMPARE(w.learningCurve()->points().back().mode, guidance::TrainingMode::kPositionControl);
    QCOMPARE(w.learningCurve()->points().back().shape, w.lastScores()->shape());
    QCOMPARE(w.learningCurve()->points().back().force, w.lastScores()->force());
    {
      // Drawn: the trial's two points in PCONTROL's colour, and nothing else in it (the panels
      // are not filled).
      const QImage curve = w.learningCurve()->grab().toImage();
      const QColor colour = LearningCurve::modeColour(guidance::TrainingMode::kPositionControl);
      int coloured = 0;
      for (int y = 0; y < curve.height(); ++y) {
        for (int x = 0; x < curve.width(); ++x) coloured += test::colourNear(curve, QPoint(x, y), colour, 0, 40) ? 1 : 0;
      }
      const double share = static_cast<double>(coloured) / (curve.width() * curve.height());
      QVERIFY2(coloured >= 2 && share < 0.01, qPrintable(QString("%1 pixels (%2) in the mode's colour").arg(coloured).arg(share)));
    }
    QCOMPARE(w.lastTrial()->metadata().extra.at("mode"), std::string("PCONTROL"));
    QCOMPARE(w.lastTrial()->metadata().extra.at("reference_file"), expert_file_.filename().string());
    QCOMPARE(w.lastTrial()->metadata().extra.at("end_reason"), std::string("pen lifted"));
    QVERIFY(w.lastTrial()->duration_s() < 3.0 * expert_.duration_s() - 0.5);

    // Let a few frames draw, then the screenshot.
    QTest::qWait(100);
    const QImage shot = w.grab().toImage();
    const QString path = QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_smoke.png");
    QVERIFY(shot.save(path));
    qInfo("screenshot: %s", qPrintable(path));

    // The paper: light, with its grain (gray levels vary) where nothing is drawn.
    const PaperView* view = w.paperView();
    const QPoint origin = view->mapTo(&w, QPoint(0, 0));
    const QPointF corner = view->mapping().toWidget(0.050, 0.030) + QPointF(origin);
    int lo = 255, hi = 0;
    double sum = 0.0;
    for (int dy = 0; dy < 30; ++dy) {
      for (int dx = 0; dx < 30; ++dx) {
        const int g = qGray(shot.pixel(corner.toPoint() + QPoint(dx, dy)));
        lo = std::min(lo, g);
        hi = std::max(hi, g);
        sum += g;
      }
    }
    QVERIFY2(sum / 900.0 > 170.0, "the paper is light");
    QVERIFY2(hi - lo >= 8, "the paper shows its grain");
    // The reference where the expert wrote, the trail where the pen wrote.
    const double reference = shareDrawn(shot, w, expert_, PaperColours::reference(), 25);
    const double trail = shareDrawn(shot, w, *w.lastTrial(), PaperColours::ink(), 25);
    QVERIFY2(reference > 0.7, qPrintable(QString("reference drawn at %1 of its points").arg(reference)));
    QVERIFY2(trail > 0.7, qPrintable(QString("trail drawn at %1 of its points").arg(trail)));
    // The status bar shows the input and the loop.
    QString status;
    for (const QLabel* label : w.statusBar()->findChildren<QLabel*>()) status += label->text() + " ";
    QVERIFY2(status.contains("Input: mouse") && status.contains("Hz") && status.contains("overruns") &&
                 status.contains("faults"),
             qPrintable(status));
  }

  // The 3-D view beside the paper: the relief's shaded mesh, and the pen's barrel where its
  // tilt puts it (two azimuths, two places), gone when there is no pen.
  void theThreeDViewShowsThePenAtItsTiltOverTheRelief() {
    MainWindow& w = *window_;
    QVERIFY(!w.sceneView()->isVisible());  // hidden until asked for
    w.setSceneShown(true);
    PenSceneView* scene = w.sceneView();
    QVERIFY(scene->isVisible());
    QVERIFY2(scene->exaggeration() > 1.0, "the default paper's grain is raised to be seen");
    constexpr double kDeg = std::numbers::pi / 180.0;
    const auto barrelAt = [](const QImage& image, const QPointF& p) {
      // The barrel's colour (or its highlight) within 2 px of p.
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const QColor c = image.pixelColor(p.toPoint() + QPoint(dx, dy));
          const QColor b = PaperColours::barrel(), h = PaperColours::barrel().lighter(160);
          const auto near = [&](const QColor& k) {
            return std::abs(c.red() - k.red()) + std::abs(c.green() - k.green()) + std::abs(c.blue() - k.blue()) < 30;
          };
          if (near(b) || near(h)) return true;
        }
      }
      return false;
    };
    std::vector<std::pair<QPointF, QPointF>> barrels;
    QImage with_pen;
    for (const double azimuth : {90.0 * kDeg, 270.0 * kDeg}) {
      Sample pen;
      pen.p_WT = Vec3(0.0, 0.0, 0.005);
      pen.tilt_altitude_rad = 50.0 * kDeg;
      pen.tilt_azimuth_rad = azimuth;
      w.paperView()->setPen(pen);
      with_pen = scene->grab().toImage();
      const auto [tip, top] = scene->barrelPx(pen);
      QVERIFY(scene->rect().contains(tip.toPoint()) && scene->rect().contains(top.toPoint()));
      const QPointF middle = 0.5 * (tip + top);
      QVERIFY2(barrelAt(with_pen, middle), qPrintable(QString("no barrel at (%1, %2)").arg(middle.x()).arg(middle.y())));
      barrels.emplace_back(tip, top);
    }
    // Toward +x the barrel leans right of its tip, toward -x left.
    QVERIFY(barrels[0].second.x() > barrels[0].first.x() + 10.0);
    QVERIFY(barrels[1].second.x() < barrels[1].first.x() - 10.0);
    with_pen.save(QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_scene_3d.png"));
    // No pen, no barrel.
    w.paperView()->setPen(std::nullopt);
    const QImage without = scene->grab().toImage();
    QVERIFY(!barrelAt(without, 0.5 * (barrels[1].first + barrels[1].second)));
    // The relief: inside one 10 mm cell of the paper's grid (no grid line, no trail), many
    // shades of the lit paper; the same cell of flat paper is one colour.
    const auto shadesInACell = [&](const QImage& image) {
      QSet<QRgb> shades;
      for (double x = -0.058; x <= -0.052; x += 0.0005) {
        for (double y = 0.032; y <= 0.038; y += 0.0005) {
          const Eigen::Vector2d at = scene->camera().toPixels(scene->drawnPoint(Vec3(x, y, 0.0)));
          shades.insert(image.pixel(static_cast<int>(at.x()), static_cast<int>(at.y())));
        }
      }
      return shades.size();
    };
    const auto grain = shadesInACell(without);
    QVERIFY2(grain > 8, qPrintable(QString("%1 shades in a cell of the paper").arg(grain)));
    QVERIFY(w.rig().environment() != nullptr);
    const DeviceLimits& limits = w.rig().environment()->limits();
    scene->setPaper(render::HeightField{}, limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                    limits.workspace_max_m.x(), limits.workspace_max_m.y());
    QCOMPARE(shadesInACell(scene->grab().toImage()), qsizetype{1});
    scene->setPaper(w.rig().environment()->paper().relief(), limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                    limits.workspace_max_m.x(), limits.workspace_max_m.y());
    w.grab().save(QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_smoke_3d.png"));
    w.setSceneShown(false);
    QVERIFY(!scene->isVisible());
  }

  void aTakeIsRecordedAndSavedButNeverOverwrittenUnasked() {
    MainWindow& w = *window_;
    w.tabs()->setCurrentIndex(MainWindow::kTabRecord);
    QVERIFY2(w.startRecording(), qPrintable(w.lastError()));
    QCOMPARE(w.activity(), MainWindow::Activity::kRecording);
    QTest::qWait(400);  // settle
    driveFor(w, 0.6, Vec3(-0.02, 0.0, 0.0));
    QVERIFY(w.stopRecording());
    QVERIFY(w.take().has_value());
    QVERIFY(w.take()->penDownCount() > 100);
    // Loading a reference now shows the reference alone: the take's force curves go (issue 18).
    QVERIFY(!w.plot()->trainee().empty());
    QVERIFY(!w.learningCurve()->points().empty());  // the first test's trial
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));
    QVERIFY(w.plot()->trainee().empty());
    QVERIFY(w.learningCurve()->points().empty());  // a new reference starts a new curve
    const QString file = QString::fromStdString((dir_ / "take.csv").string());
    QVERIFY2(w.saveTake(file), qPrintable(w.lastError()));
    const HapticProfile saved = io::readProfileCsv(file.toStdString());
    QCOMPARE(saved.metadata().subject, std::string("Ana"));
    QCOMPARE(saved.metadata().skill, std::string("eight"));
    QCOMPARE(saved.size(), w.take()->size());
    // Saving again is refused (the question is answered no) and the file is untouched.
    const auto size = std::filesystem::file_size(file.toStdString());
    QVERIFY(!w.saveTake(file));
    QVERIFY2(w.lastError().contains("already exists"), qPrintable(w.lastError()));
    QCOMPARE(std::filesystem::file_size(file.toStdString()), size);

    // The take as the reference (saved above as take.csv): the Train tab opens on it, and a trial
    // runs against it.
    w.tabs()->setCurrentIndex(MainWindow::kTabRecord);
    QVERIFY2(w.useTakeAsReference(), qPrintable(w.lastError()));
    QCOMPARE(w.tabs()->currentIndex(), int{MainWindow::kTabTrain});
    Trail take_trail;
    take_trail.assign(*w.take());
    QCOMPARE(w.paperView()->reference().pointCount(), take_trail.pointCount());
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    QVERIFY(w.rig().spec().reference != nullptr);
    // Saved before it became the reference: it is named by its file.
    QCOMPARE(w.rig().spec().metadata.extra.at("reference_file"), std::string("take.csv"));
    QCOMPARE(w.rig().spec().metadata.skill, w.take()->metadata().skill);
    w.abortActivity();
    // A new take, unsaved, as the reference: "take (not saved)"; saved, its file names it.
    QVERIFY2(w.startRecording(), qPrintable(w.lastError()));
    QTest::qWait(400);  // settle
    driveFor(w, 0.6, Vec3(0.02, 0.0, 0.0));
    QVERIFY(w.stopRecording());
    QVERIFY2(w.useTakeAsReference(), qPrintable(w.lastError()));
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    QCOMPARE(w.rig().spec().metadata.extra.at("reference_file"), std::string("take (not saved)"));
    w.abortActivity();
    const QString second = QString::fromStdString((dir_ / "take2.csv").string());
    QVERIFY2(w.saveTake(second), qPrintable(w.lastError()));
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    QCOMPARE(w.rig().spec().metadata.extra.at("reference_file"), std::string("take2.csv"));
    w.abortActivity();
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));

    // With the pen-down trigger the take starts at the pen's touch and ends by itself a second
    // after the pen is lifted (the Record tab watches the rig).
    QComboBox* trigger = w.recordTab()->widgets().trigger;
    trigger->setCurrentIndex(0);
    QVERIFY2(w.startRecording(), qPrintable(w.lastError()));
    QTest::qWait(400);  // settle
    driveFor(w, 0.6, Vec3(-0.01, -0.01, 0.0));
    QCOMPARE(w.activity(), MainWindow::Activity::kRecording);
    QTRY_COMPARE_WITH_TIMEOUT(w.activity(), MainWindow::Activity::kFree, 3000);
    QVERIFY(w.take().has_value());
    QVERIFY(w.take()->penDownCount() > 100);
    QVERIFY(w.take()->samples().front().pen_down);  // nothing before the touch
    trigger->setCurrentIndex(1);
  }

  void aStudyTrialIsStoredAndReviewed() {
    MainWindow& w = *window_;
    std::ofstream(dir_ / "study.json") << test::smallStudyJson(
        "[\"pcontrol\"]", 1.0, "[{\"id\": \"P01\", \"participant\": \"person\"}]", "grain",
        "\"trial_end\": {\"pen_up_s\": 0.5}");
    const auto db_file = dir_ / "study.sqlite";
    { (void)session::StudyDatabase::create(db_file, session::loadStudy(dir_ / "study.json")); }
    QVERIFY2(w.openStudy(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QVERIFY2(w.selectStudySubject("P01"), qPrintable(w.lastError()));
    QCOMPARE(w.study()->state(), StudySession::State::kReady);
    QVERIFY(w.studyNext());
    QCOMPARE(w.activity(), MainWindow::Activity::kStudyTrial);
    QCOMPARE(w.rig().spec().pen_up_end_s, 0.5);
    const double max_s = w.rig().spec().duration_s;
    double ran_s = 0.0;
    driveAlongExpert(w, Vec3(0.003, 0.002, 0.0), MainWindow::Activity::kStudyTrial, nullptr, &ran_s);
    QVERIFY2(ran_s < max_s - 0.5, qPrintable(QString("ran %1 s of a %2 s maximum").arg(ran_s).arg(max_s)));
    QCOMPARE(w.study()->completedCount(), 1);
    QCOMPARE(w.study()->state(), StudySession::State::kResting);
    // The trial showed its reference; the next is recall: its reference is out of sight from its
    // announcement on, the rest included, on the paper and on the plot.
    QVERIFY(!w.study()->currentTrial()->plan.view.show_reference);
    QVERIFY(!w.paperView()->referenceShown());
    QVERIFY(w.plot()->expert().empty());
    w.closeStudy();

    // Stored through the library: readable, completed, with the runner's metadata.
    {
      const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
      const auto trials = db.trials("P01");
      QCOMPARE(trials[0].status, session::TrialStatus::kCompleted);
      QVERIFY(trials[0].outcome.starts_with("ok: "));
      const HapticProfile stored = db.trialProfile(trials[0].id);
      QCOMPARE(stored.metadata().extra.at("study_mode"), std::string("PCONTROL"));
      QCOMPARE(stored.metadata().extra.at("end_reason"), std::string("pen lifted"));
      QCOMPARE(stored.metadata().created_utc, std::string());
    }

    // Review: overlay and play back.
    QVERIFY2(w.openReview(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
    QVERIFY2(w.showReviewTrial(db.trials("P01")[0].id), qPrintable(w.lastError()));
    QVERIFY(!w.paperView()->overlay().empty());
    w.togglePlayback();
    QCOMPARE(w.activity(), MainWindow::Activity::kPlayback);
    QTest::qWait(300);
    QVERIFY(!w.paperView()->trail().empty());
    w.grab().save(QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_review.png"));

    // Opening a study after Review leaves nothing of the reviewed trial on show (it was drawn
    // in orange), and stops its playback (issue 18).
    QVERIFY2(w.openStudy(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QVERIFY(w.paperView()->overlay().empty());
    QVERIFY(w.paperView()->trail().empty());
    // A training trial runs on the open study's paper: the study cannot close under it.
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    w.closeStudy();
    QVERIFY(w.study() != nullptr);
    QCOMPARE(w.activity(), MainWindow::Activity::kTrial);
    w.abortActivity();
    w.closeStudy();
    QVERIFY(w.study() == nullptr);

    // Opening another study for review forgets the first one's trial and scores.
    QVERIFY2(w.showReviewTrial(db.trials("P01")[0].id), qPrintable(w.lastError()));
    auto* scores = w.findChild<QLabel*>("review_scores");
    QVERIFY(scores != nullptr);
    QVERIFY(!scores->text().isEmpty());
    const auto other = dir_ / "other-review.sqlite";
    std::filesystem::copy_file(db_file, other, std::filesystem::copy_options::overwrite_existing);
    QVERIFY2(w.openReview(QString::fromStdString(other.string())), qPrintable(w.lastError()));
    QVERIFY(scores->text().isEmpty());
    QVERIFY(w.paperView()->overlay().empty());
    w.togglePlayback();  // nothing to play: the old trial is gone
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
  }

  // A person's study over two days (issue 35): after the first day's session the studio offers
  // the next session with its date, asks before beginning it early, and runs it.
  void aPersonsStudyOverTwoDaysOffersTheNextSession() {
    MainWindow& w = *window_;
    std::ofstream(dir_ / "design.json") << test::designStudyJson(0.5);
    const auto db_file = dir_ / "design.sqlite";
    { (void)session::StudyDatabase::create(db_file, session::loadStudy(dir_ / "design.json")); }
    QVERIFY2(w.openStudy(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    auto* subjects = w.findChild<QComboBox*>("study_subject");
    QVERIFY(subjects != nullptr);
    QVERIFY2(subjects->itemText(0).contains("next: session 1 of 2 (day 0), any time"), qPrintable(subjects->itemText(0)));
    QVERIFY2(w.selectStudySubject("P01"), qPrintable(w.lastError()));
    for (int trial = 0; trial < 2; ++trial) {  // day 0: training, then the post-test
      QVERIFY(w.studyNext());
      driveAlongExpert(w, Vec3(0.003, 0.002, 0.0), MainWindow::Activity::kStudyTrial, nullptr, nullptr);
    }
    QCOMPARE(w.study()->completedCount(), 2);
    QCOMPARE(w.study()->state(), StudySession::State::kNextSession);
    const QString tomorrow = QString::fromStdString(session::addDays(session::localToday(), 1).iso());
    auto* next = w.findChild<QPushButton*>("study_next");
    auto* prompt = w.findChild<QLabel*>("study_prompt");
    QVERIFY(next != nullptr && prompt != nullptr);
    QCOMPARE(next->text(), "Begin session 2 early (due " + tomorrow + ")");
    QVERIFY(next->isEnabled());
    QVERIFY2(prompt->text().contains("Next session for P01: session 2 of 2 (day 1), due on " + tomorrow + " (in 1 day): early"),
             qPrintable(prompt->text()));
    w.grab().save(QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_next_session.png"));
    QVERIFY(!w.studyNext());  // "begin it early?" no
    QCOMPARE(w.study()->state(), StudySession::State::kNextSession);
    w.setInteractive(false, true);
    QVERIFY(w.studyNext());  // yes
    w.setInteractive(false);
    QCOMPARE(w.study()->state(), StudySession::State::kReady);
    QVERIFY(prompt->text().contains("Retention: trial 1 of 1"));
    QVERIFY(w.studyNext());
    driveAlongExpert(w, Vec3(0.003, 0.002, 0.0), MainWindow::Activity::kStudyTrial, nullptr, nullptr);
    QCOMPARE(w.study()->state(), StudySession::State::kFinished);
    w.closeStudy();
    const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
    const auto trials = db.trials("P01");
    QCOMPARE(trials.size(), std::size_t{3});
    for (const auto& t : trials) QCOMPARE(t.status, session::TrialStatus::kCompleted);
    QCOMPARE(db.trialProfile(trials[2].id).metadata().extra.at("session"), std::string("2"));
  }

  // Ctrl+. ends a trial now and keeps it: a training trial is scored, a study trial stored,
  // both with end_reason "stopped"; during the get-ready phase it keeps nothing.
  void theStopKeyEndsATrialAndKeepsIt() {
    MainWindow& w = *window_;
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    w.tabs()->setCurrentIndex(MainWindow::kTabTrain);
    w.paperView()->setFocus();
    const auto stop_key = [&w] { QTest::keyClick(&w, Qt::Key_Period, Qt::ControlModifier); };

    // Still getting ready: nothing recorded, nothing kept.
    const HapticProfile before = *w.lastTrial();
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    stop_key();
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QVERIFY(*w.lastTrial() == before);
    QVERIFY2(w.statusBar()->currentMessage().contains("nothing kept"), qPrintable(w.statusBar()->currentMessage()));

    // Writing, the pen down: stopped, kept, scored.
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    writeUntilStopped(w, MainWindow::Activity::kTrial, stop_key);
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QVERIFY(w.lastTrial()->size() > 300);
    QCOMPARE(w.lastTrial()->metadata().extra.at("end_reason"), std::string("stopped"));
    QVERIFY(w.lastScores().has_value());

    // A study trial ended by the stop key is stored like any other.
    const auto db_file = dir_ / "study.sqlite";
    QVERIFY2(w.openStudy(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QVERIFY2(w.selectStudySubject("P01"), qPrintable(w.lastError()));
    QCOMPARE(w.study()->completedCount(), 1);
    w.setMode(guidance::TrainingMode::kForceControl);  // the Train tab's mode, not the trial's
    QVERIFY(w.studyNext());  // cuts the rest short
    QCOMPARE(w.activity(), MainWindow::Activity::kStudyTrial);
    // A recall trial runs unassisted, and the status bar says so whatever the Train tab's mode (issue 18).
    QCOMPARE(w.rig().spec().guidance.mode, guidance::TrainingMode::kBasic);
    auto* activity_status = w.findChild<QLabel*>("status_activity");
    QVERIFY(activity_status != nullptr);
    QTRY_VERIFY_WITH_TIMEOUT(activity_status->text().contains("mode BASIC"), 1000);
    writeUntilStopped(w, MainWindow::Activity::kStudyTrial, stop_key);
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QCOMPARE(w.study()->state(), StudySession::State::kFinished);
    w.closeStudy();
    const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
    const auto trials = db.trials("P01");
    QCOMPARE(trials[1].status, session::TrialStatus::kCompleted);
    const HapticProfile stored = db.trialProfile(trials[1].id);
    QCOMPARE(stored.metadata().extra.at("end_reason"), std::string("stopped"));
    QCOMPARE(stored.metadata().extra.at("phase"), std::string("recall"));
    QVERIFY(stored.size() > 300);
  }

  void shortcutsSwitchModesAndStartTrials() {
    MainWindow& w = *window_;
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    w.tabs()->setCurrentIndex(MainWindow::kTabTrain);
    w.paperView()->setFocus();
    QTest::keyClick(&w, Qt::Key_3);
    QCOMPARE(w.mode(), guidance::TrainingMode::kForceControl);
    QTest::keyClick(&w, Qt::Key_1);
    QCOMPARE(w.mode(), guidance::TrainingMode::kBasic);
    QTest::keyClick(&w, Qt::Key_Space);  // the Train tab's main action: start a trial
    QVERIFY2(w.activity() == MainWindow::Activity::kTrial, qPrintable(w.lastError()));
    QCOMPARE(w.rig().spec().guidance.mode, guidance::TrainingMode::kBasic);
    // A scheduled strategy is not switched into mid-trial (its gain is set before a trial).
    w.setMode(guidance::TrainingMode::kFading);
    QCOMPARE(w.mode(), guidance::TrainingMode::kBasic);
    QVERIFY2(w.lastError().contains("Less help each time sets its guidance before each trial"), qPrintable(w.lastError()));
    QTest::keyClick(&w, Qt::Key_Escape);
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
  }

  // Issue 38: a reference pressing harder than the pen renders loads (the device may change
  // before a trial), and the trial is refused at its start with the numbers and the remedy.
  void aReferenceThePenCannotRenderIsRefusedWhenATrialStarts() {
    MainWindow& w = *window_;
    std::vector<Sample> samples = expert_.samples();
    for (Sample& s : samples) s.f_user_W *= 3.0;  // the expert presses about 1 N: now about 3 N
    const auto heavy_file = dir_ / "heavy.csv";
    io::writeProfileCsv(HapticProfile::fromSamples(expert_.metadata(), expert_.rawChannels(), std::move(samples), false),
                        heavy_file);
    QVERIFY2(w.loadReference(QString::fromStdString(heavy_file.string())), qPrintable(w.lastError()));
    w.tabs()->setCurrentIndex(MainWindow::kTabTrain);
    QVERIFY(!w.startTrial());
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    for (const char* part : {"the reference: it presses up to", "continuous force of 1.75 N", "--scale-force"}) {
      QVERIFY2(w.lastError().contains(part), qPrintable(w.lastError()));
    }
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));
  }

  // Issue 39: a letter of the library, written by the simulated expert, is the reference: chosen
  // in the Train tab's list by its character, named in the trial's metadata, remembered (below).
  void aLetterWrittenByTheSimulatedExpertIsTheReference() {
    MainWindow& w = *window_;
    w.tabs()->setCurrentIndex(MainWindow::kTabTrain);
    QComboBox* letters = w.trainTab()->widgets().letter;
    QCOMPARE(letters->count(), 1 + 64);  // "choose one", then the 62 letters and digits, ந and the loop
    const int a = letters->findData(QString("small-a"));
    QVERIFY(a > 0);
    QCOMPARE(letters->itemText(a), QString("a   (small-a)"));
    letters->setCurrentIndex(a);
    emit letters->activated(a);
    const HapticProfile* reference = w.trainTab()->reference();
    QVERIFY(reference != nullptr);
    QCOMPARE(reference->metadata().skill, std::string("small-a"));
    QVERIFY(reference->penDownCount() > 500);  // the a: about 1 s of its 1.9 s with the pen down, at 1 kHz
    const QString label = w.trainTab()->widgets().reference->text();
    QVERIFY2(label.contains("the letter <b>a</b> (small-a) written by the simulated expert"), qPrintable(label));
    QVERIFY2(w.startTrial(), qPrintable(w.lastError()));
    QCOMPARE(w.rig().spec().metadata.skill, std::string("small-a"));
    QCOMPARE(w.rig().spec().metadata.extra.at("reference_file"), std::string("glyph:small-a"));
    w.abortActivity();
    // A name that is no built-in glyph is refused, and the reference stays.
    QVERIFY(!w.trainTab()->useLetter("zz"));
    QVERIFY2(w.lastError().contains("no built-in glyph has that name or character"), qPrintable(w.lastError()));
    QCOMPARE(w.trainTab()->reference()->metadata().skill, std::string("small-a"));
    QCOMPARE(letters->currentIndex(), a);
  }

  void settingsAreRememberedAcrossSessions() {
    const QString ini = QString::fromStdString((dir_ / "studio.ini").string());
    // Every strategy but the mentored ones is offered by its plain name, the technical beside;
    // one past the paper's three is remembered.
    const QComboBox* modes = window_->trainTab()->widgets().mode;
    QCOMPARE(modes->count(), static_cast<int>(guidance::kLastMode) + 1 - 4);
    QCOMPARE(modes->itemText(1), QString("Guided path — PCONTROL"));
    QCOMPARE(modes->itemText(modes->count() - 2), QString("Help when needed — ASSIST-AS-NEEDED"));
    window_->setMode(guidance::TrainingMode::kAssistAsNeeded);
    QCOMPARE(modes->currentText(), QString("Help when needed — ASSIST-AS-NEEDED"));
    window_->setSceneShown(true);
    window_->setInteractive(false, true);  // "quit and lose the unsaved trial?" yes
    QVERIFY(window_->close());
    window_.reset();
    MainWindow again(std::make_unique<QSettings>(ini, QSettings::IniFormat));
    again.setInteractive(false, true);
    QCOMPARE(again.mode(), guidance::TrainingMode::kAssistAsNeeded);
    QVERIFY(!again.sceneView()->isHidden());  // the 3-D view shown last time is shown again
    QVERIFY(again.startTrial());  // the reference of last time is written again: the letter a
    QCOMPARE(again.trainTab()->reference()->metadata().skill, std::string("small-a"));
    again.abortActivity();
    {
      const QSettings letter(ini, QSettings::IniFormat);
      QCOMPARE(letter.value("train/reference_letter").toString(), QString("small-a"));
      QVERIFY(!letter.contains("train/reference_file"));
    }
    // A file after the letter: the file is remembered, the letter forgotten.
    QVERIFY2(again.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(again.lastError()));
    QVERIFY(again.close());
    QSettings settings(ini, QSettings::IniFormat);
    QCOMPARE(settings.value("train/reference_file").toString(), QString::fromStdString(expert_file_.string()));
    QVERIFY(!settings.contains("train/reference_letter"));
    QCOMPARE(settings.value("record/name").toString(), QString("Ana"));
    QCOMPARE(settings.value("train/settle_s").toDouble(), 0.5);
  }

 private:
  /// The scripted hand writing the expert (test::writeAlong).
  void driveAlongExpert(MainWindow& w, const Vec3& offset, MainWindow::Activity during,
                        const char* mid_shot = nullptr, double* ran_s = nullptr) {
    test::writeAlong(w, expert_, offset, during, mid_shot, ran_s);
  }

  /// Holds the left button and writes along the expert's path (on the trial's clock) until
  /// 0.5 s of the trial have passed, then presses `stop` with the pen still down.
  void writeUntilStopped(MainWindow& w, MainWindow::Activity during, const std::function<void()>& stop) {
    PaperView* view = w.paperView();
    const auto at = [&](double t_trial) {
      Playback where;
      where.load(&expert_);
      return view->mapping().toWidget(expert_[where.indexAt(std::max(0.0, t_trial))].p_WT);
    };
    sendMouse(view, QEvent::MouseMove, at(0.0), Qt::NoButton, Qt::NoButton);
    sendMouse(view, QEvent::MouseButtonPress, at(0.0), Qt::LeftButton, Qt::LeftButton);
    QElapsedTimer timer;
    timer.start();
    double t_trial = -1.0;
    while (w.activity() == during && t_trial < 0.5 && timer.elapsed() < 15000) {
      t_trial = w.rig().status().loop_time_s - w.rig().spec().settle_s;
      sendMouse(view, QEvent::MouseMove, at(t_trial), Qt::NoButton, Qt::LeftButton);
      QTest::qWait(8);
    }
    QCOMPARE(w.activity(), during);  // still running: the end rule or the maximum did not end it
    stop();
    sendMouse(view, QEvent::MouseButtonRelease, at(t_trial), Qt::LeftButton, Qt::NoButton);
  }

  /// Holds the left button and moves the mouse along a short line for `seconds`.
  void driveFor(MainWindow& w, double seconds, const Vec3& start) {
    PaperView* view = w.paperView();
    sendMouse(view, QEvent::MouseButtonPress, view->mapping().toWidget(start), Qt::LeftButton, Qt::LeftButton);
    QElapsedTimer timer;
    timer.start();
    while (static_cast<double>(timer.elapsed()) < seconds * 1000.0) {
      const double t = static_cast<double>(timer.elapsed()) * 1e-3;
      sendMouse(view, QEvent::MouseMove,
                view->mapping().toWidget(start + Vec3(0.03 * t, 0.01 * std::sin(8.0 * t), 0.0)), Qt::NoButton,
                Qt::LeftButton);
      QTest::qWait(8);
    }
    sendMouse(view, QEvent::MouseButtonRelease, view->mapping().toWidget(start), Qt::LeftButton, Qt::NoButton);
    QTest::qWait(100);
  }

  std::filesystem::path dir_;
  HapticProfile expert_;
  std::filesystem::path expert_file_;
  std::unique_ptr<MainWindow> window_;
};

QTEST_MAIN(StudioSmokeTest)
#include "studio_smoke_test.moc"
