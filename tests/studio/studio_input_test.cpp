// The studio's inputs and outputs beyond the mouse: a pen tablet as the hand (pressure through
// the tablet calibration, tilt as the pen's angles, QTabletEvent on the paper view), the device
// picked by URI (validated by the library, remembered), and the analysis report of a reviewed
// study written next to its database and handed to a URL opener (no browser in tests).
#include <QLabel>
#include <QPointingDevice>
#include <QStatusBar>
#include <QTabletEvent>
#include <QPushButton>
#include <QTimer>
#include <QTreeWidget>
#include <QTemporaryDir>
#include <QtTest>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <tuple>

#include "core/device_choice.hpp"
#include "support/background_process.hpp"
#include "core/mouse_hand.hpp"
#include "core/study_report_export.hpp"
#include "core/tablet_input.hpp"
#include "hattr/net/device_server.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/report/study_analysis.hpp"
#include "studio_test_support.hpp"
#include "ui/main_window.hpp"
#include "ui/paper_view.hpp"
#include "ui/review_tab.hpp"

using namespace hattr;
using namespace hattr::studio;

namespace {

constexpr double kDeg = 3.141592653589793 / 180.0;

/// The Review tree's costs, by trial id: (shape, force, status) as the tree shows them.
std::map<qint64, std::tuple<QString, QString, QString>> treeCosts(const ReviewTab& review) {
  std::map<qint64, std::tuple<QString, QString, QString>> shown;
  QTreeWidget* tree = review.widgets().tree;
  for (int s = 0; s < tree->topLevelItemCount(); ++s) {
    for (int t = 0; t < tree->topLevelItem(s)->childCount(); ++t) {
      const QTreeWidgetItem* item = tree->topLevelItem(s)->child(t);
      if (!item->data(ReviewTab::kTrial, Qt::UserRole).isValid()) continue;
      shown[item->data(ReviewTab::kTrial, Qt::UserRole).toLongLong()] = {
          item->text(ReviewTab::kShape), item->text(ReviewTab::kForce), item->text(ReviewTab::kStatus)};
    }
  }
  return shown;
}

/// Checks that the tree shows exactly `costs` (to 4 digits) on their trials and nothing on the others.
void expectTreeShows(const ReviewTab& review, const std::vector<report::TrialCost>& costs) {
  auto shown = treeCosts(review);
  QVERIFY(!costs.empty());
  for (const report::TrialCost& c : costs) {
    const auto it = shown.find(c.trial_id);
    QVERIFY2(it != shown.end(), qPrintable(QString("trial %1 is not in the tree").arg(c.trial_id)));
    QCOMPARE(std::get<0>(it->second), QString::number(c.trajectory(), 'g', 4));
    QCOMPARE(std::get<1>(it->second), QString::number(c.forceProfile(), 'g', 4));
    shown.erase(it);
  }
  // The training trials (completed, not analyzed) show no cost.
  QVERIFY(!shown.empty());
  for (const auto& [id, texts] : shown) QVERIFY2(std::get<0>(texts).isEmpty(), qPrintable(QString::number(id)));
}

QString thrownMessage(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& e) {
    return QString::fromUtf8(e.what());
  }
  return {};
}

QString inputStatus(const MainWindow& w) {
  for (const QLabel* label : w.statusBar()->findChildren<QLabel*>()) {
    if (label->text().startsWith("Input:")) return label->text();
  }
  return {};
}

}  // namespace

class StudioInputTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { dir_ = studio::test::freshTempDir("input"); }
  void cleanupTestCase() {
    window_.reset();
    std::filesystem::remove_all(dir_);
  }

  // ---- Tablet mapping (core, no widgets) ----
  void tiltBecomesAltitudeAndAzimuth() {
    const PenAngles upright = penAnglesFromTilt(0.0, 0.0);
    QVERIFY(std::abs(upright.altitude_rad - 90.0 * kDeg) < 1e-12);
    // Barrel leaning right by 30°: altitude 60°, azimuth 90° (clockwise from +y).
    const PenAngles right = penAnglesFromTilt(30.0, 0.0);
    QVERIFY(std::abs(right.altitude_rad - 60.0 * kDeg) < 1e-9);
    QVERIFY(std::abs(right.azimuth_rad - 90.0 * kDeg) < 1e-9);
    // Qt's +yTilt is toward the writer: W's −y, azimuth 180°.
    const PenAngles toward = penAnglesFromTilt(0.0, 30.0);
    QVERIFY(std::abs(toward.altitude_rad - 60.0 * kDeg) < 1e-9);
    QVERIFY(std::abs(toward.azimuth_rad - 180.0 * kDeg) < 1e-9);
    QVERIFY(std::abs(penAnglesFromTilt(0.0, -30.0).azimuth_rad) < 1e-9);
    QVERIFY(std::abs(penAnglesFromTilt(-30.0, 0.0).azimuth_rad - 270.0 * kDeg) < 1e-9);
    // Both tilts: the barrel's angle from the vertical is atan(√(tan²x + tan²y)).
    const PenAngles both = penAnglesFromTilt(45.0, 45.0);
    QVERIFY(std::abs(both.altitude_rad - (90.0 * kDeg - std::atan(std::sqrt(2.0)))) < 1e-9);
    QVERIFY(std::abs(both.azimuth_rad - 135.0 * kDeg) < 1e-9);  // the writer's lower right
    // Almost flat is clamped; nonsense gives an upright pen.
    QVERIFY(std::abs(penAnglesFromTilt(89.9, 0.0).altitude_rad - kTabletMinAltitude_rad) < 1e-12);
    QVERIFY(std::abs(penAnglesFromTilt(std::nan(""), 0.0).altitude_rad - 90.0 * kDeg) < 1e-12);
  }

  void pressureGoesThroughTheTabletCalibration() {
    const io::TabletCalibration cal = defaultTabletCalibration();
    QCOMPARE(cal.pressure_max_N, io::svc2004Calibration().pressure_max_N);
    QCOMPARE(tabletPressureToNewtons(0.0, cal), 0.0);
    QVERIFY(std::abs(tabletPressureToNewtons(1.0, cal) - cal.pressure_max_N) < 1e-12);
    QVERIFY(std::abs(tabletPressureToNewtons(0.5, cal) - 0.5 * cal.pressure_max_N) < 1e-12);
    QVERIFY(std::abs(tabletPressureToNewtons(1.7, cal) - cal.pressure_max_N) < 1e-12);  // clamped
    QVERIFY(std::abs(tabletPressureToNewtons(0.5, cal) - io::pressureToNewtons(0.5 * cal.pressure_max_raw, cal)) <
            1e-12);
    // A calibration file overrides the full scale and the curve.
    const auto file = dir_ / "cal.json";
    std::ofstream(file) << "{\"pressure_max_N\": 3.5, \"pressure_exponent\": 2.0}";
    const io::TabletCalibration custom = loadTabletCalibration(file);
    QVERIFY(std::abs(tabletPressureToNewtons(1.0, custom) - 3.5) < 1e-12);
    QVERIFY(std::abs(tabletPressureToNewtons(0.5, custom) - 3.5 * 0.25) < 1e-12);
    std::ofstream(dir_ / "bad.json") << "{\"pressure_max_M\": 3.5}";
    QVERIFY(thrownMessage([&] { (void)loadTabletCalibration(dir_ / "bad.json"); }).contains("pressure_max_M"));
  }

  void aTabletInputDrivesTheHandsAnglesAndPress() {
    MouseHand hand;
    MouseInput input;
    input.pen_down = true;
    input.press_N = 1.2;
    input.tablet = true;
    input.tablet_press_N = 2.0;
    input.altitude_rad = 50.0 * kDeg;
    input.azimuth_rad = 30.0 * kDeg;
    hand.setInput(input);
    const device::HandCommand c = hand.command(0.0);
    QCOMPARE(c.press_N, 2.0);
    QCOMPARE(c.altitude_rad, 50.0 * kDeg);
    QCOMPARE(c.azimuth_rad, 30.0 * kDeg);
    // The mouse again: its press and the fixed 60° tilt.
    input.tablet = false;
    hand.setInput(input);
    hand.rewind();
    const device::HandCommand m = hand.command(1.0);
    QCOMPARE(m.press_N, 1.2);
    QCOMPARE(m.altitude_rad, hand.params().altitude_rad);
  }

  // ---- The window ----
  void aTabletEventOnThePaperDrivesTheHand() {
    MainWindow& w = window();
    (void)w.rig().finish();  // the servo thread stops reading the hand: the test reads it
    PaperView* view = w.paperView();
    const QPointingDevice stylus("test stylus", 4242, QInputDevice::DeviceType::Stylus,
                                 QPointingDevice::PointerType::Pen,
                                 QInputDevice::Capability::Position | QInputDevice::Capability::Pressure |
                                     QInputDevice::Capability::XTilt | QInputDevice::Capability::YTilt,
                                 1, 2);
    const QPointF at(view->width() * 0.4, view->height() * 0.5);
    QTabletEvent press(QEvent::TabletPress, &stylus, at, view->mapToGlobal(at), 0.5, 30.0f, 0.0f, 0.0f, 0.0, 0.0f,
                       Qt::NoModifier, Qt::LeftButton, Qt::LeftButton);
    QVERIFY(QApplication::sendEvent(view, &press));
    QVERIFY(press.isAccepted());
    const Eigen::Vector2d expected = view->mapping().clampToPaper(view->mapping().toPaper(at));
    const MouseInput& input = w.mouseHand().input();
    QVERIFY(input.tablet);
    QVERIFY(input.pen_down);
    QVERIFY(std::abs(input.x_m - expected.x()) < 1e-12 && std::abs(input.y_m - expected.y()) < 1e-12);
    w.mouseHand().rewind();
    const device::HandCommand c = w.mouseHand().command(0.0);
    QVERIFY(c.pen_down);
    QVERIFY(std::abs(c.press_N - 0.5 * defaultTabletCalibration().pressure_max_N) < 1e-9);
    QVERIFY(std::abs(c.altitude_rad - 60.0 * kDeg) < 1e-6);
    QVERIFY(std::abs(c.azimuth_rad - 90.0 * kDeg) < 1e-6);
    QVERIFY(std::abs(c.p_target_W.x() - expected.x()) < 1e-12);
    QTRY_VERIFY_WITH_TIMEOUT(inputStatus(w).startsWith("Input: tablet"), 2000);

    // A calibration from the menu changes the force.
    const auto file = dir_ / "studio_cal.json";
    std::ofstream(file) << "{\"pressure_max_N\": 2.0}";
    QVERIFY2(w.loadTabletCalibration(QString::fromStdString(file.string())), qPrintable(w.lastError()));
    QTabletEvent move(QEvent::TabletMove, &stylus, at, view->mapToGlobal(at), 1.0, 0.0f, 0.0f, 0.0f, 0.0, 0.0f,
                      Qt::NoModifier, Qt::NoButton, Qt::LeftButton);
    QVERIFY(QApplication::sendEvent(view, &move));
    QVERIFY(std::abs(w.mouseHand().command(0.001).altitude_rad - 90.0 * kDeg) < 1e-9);
    QCOMPARE(w.mouseHand().input().tablet_press_N, 2.0);
    QTabletEvent release(QEvent::TabletRelease, &stylus, at, view->mapToGlobal(at), 0.0, 0.0f, 0.0f, 0.0f, 0.0,
                         0.0f, Qt::NoModifier, Qt::LeftButton, Qt::NoButton);
    QVERIFY(QApplication::sendEvent(view, &release));
    QVERIFY(!w.mouseHand().input().pen_down);

    // The mouse moves: it is the hand again.
    QMouseEvent mouse(QEvent::MouseMove, at, view->mapToGlobal(at), Qt::NoButton, Qt::NoButton, Qt::NoModifier);
    QApplication::sendEvent(view, &mouse);
    QVERIFY(!w.mouseHand().input().tablet);
    QTRY_VERIFY_WITH_TIMEOUT(inputStatus(w).startsWith("Input: mouse"), 2000);
  }

  void aGoodDeviceUriChangesTheRigAndABadOneIsRefused() {
    MainWindow& w = window();
    QVERIFY2(w.setDevice("sim://pen?continuous_force_N=1.2"), qPrintable(w.lastError()));
    QVERIFY(w.rig().active());
    QCOMPARE(w.rig().environment()->limits().continuous_force_N, 1.2);
    QCOMPARE(w.deviceUri(), QString("sim://pen?continuous_force_N=1.2"));

    QVERIFY(!w.setDevice("usb://x"));
    QVERIFY2(w.lastError().contains("device URI \"usb://x\": unknown scheme"), qPrintable(w.lastError()));
    QVERIFY(!w.setDevice("udp://host:9000"));
    QVERIFY2(w.lastError().contains("expected an IPv4 address"), qPrintable(w.lastError()));
    QVERIFY(!w.setDevice("plugin:/no/such/lib.so"));
    QVERIFY2(w.lastError().contains("file not found"), qPrintable(w.lastError()));
    QVERIFY(!w.setDevice("sim://pen?continuous_force_N=-1"));
    QVERIFY2(w.lastError().contains("continuous_force_N"), qPrintable(w.lastError()));
    QVERIFY(!w.setDevice("udp://127.0.0.1:9000"));
    QVERIFY2(w.lastError().contains("missing key=FILE"), qPrintable(w.lastError()));
    QVERIFY(!w.setDevice("sim://pen?mass=1"));
    QVERIFY2(w.lastError().contains("unknown key"), qPrintable(w.lastError()));
    QCOMPARE(w.deviceUri(), QString("sim://pen?continuous_force_N=1.2"));
    QCOMPARE(w.rig().environment()->limits().continuous_force_N, 1.2);

    // A driver plugin is a device like any other: the rig runs on it.
    QVERIFY2(w.setDevice("plugin:sim?continuous_force_N=1.1"), qPrintable(w.lastError()));
    QVERIFY(w.rig().active());
    QCOMPARE(w.rig().environment()->limits().continuous_force_N, 1.1);
    // And so is a pen served over the network by a device server on this machine.
    {
      const QTemporaryDir dir;
      const std::string key_file = (dir.path() + "/shared.key").toStdString();
      wire::writeKeyFile(key_file, wire::randomKey(), false);
      net::DeviceServerConfig config;
      config.device_uri = "sim://pen?continuous_force_N=0.9";
      config.key = wire::readKeyFile(key_file);
      net::DeviceServer server(config);
      server.start();
      const QString uri = QString::fromStdString("udp://" + server.endpoint().text() + "?key=" + key_file);
      QVERIFY2(w.setDevice(uri), qPrintable(w.lastError()));
      QVERIFY(w.rig().active());
      QCOMPARE(w.rig().environment()->limits().continuous_force_N, 0.9);
      QTRY_VERIFY_WITH_TIMEOUT(server.sessionLive(), 2000);
      // The free run's session is the only one: nothing opened the device to read its limits.
      QCOMPARE(server.stats().sessions, std::uint64_t{1});
      QVERIFY2(w.setDevice("sim://pen?continuous_force_N=1.2"), qPrintable(w.lastError()));
    }
    // The open pen (serial://), its firmware under the emulator.
    openPenIsADeviceLikeAnyOther(w);

    // Remembered: a new window starts on it.
    window_.reset();
    QCOMPARE(window().deviceUri(), QString("sim://pen?continuous_force_N=1.2"));
    QCOMPARE(window().rig().environment()->limits().continuous_force_N, 1.2);
    QVERIFY(window().setDevice("sim://pen"));
  }

  void openPenIsADeviceLikeAnyOther(MainWindow& w) {
    const QString emulator = qEnvironmentVariable("HATTR_PEN_EMULATOR");
    const QString firmware = qEnvironmentVariable("HATTR_OPENPEN_FIRMWARE");
    if (emulator.isEmpty() || firmware.isEmpty()) {
      qInfo("the open pen's emulator or firmware was not built (avr-gcc, simavr): serial:// not checked here");
      return;
    }
    // A port that is not there is refused with the library's message, the pen before it kept.
    QVERIFY(!w.setDevice("serial:///dev/hattr-no-such-port"));
    QVERIFY2(w.lastError().contains("/dev/hattr-no-such-port"), qPrintable(w.lastError()));
    QCOMPARE(w.deviceUri(), QString("sim://pen?continuous_force_N=1.2"));
    QVERIFY(w.rig().active());
    // The pen: the free run opens it once and the paper takes its 2-DOF limits from that open;
    // the emulator exits at the first hang-up, so an open made only to read the limits would
    // leave no pen for the run.
    const QTemporaryDir dir;
    hattr::test::BackgroundProcess pen({emulator.toStdString(), "--firmware", firmware.toStdString(), "--clock", "realtime",
                                        "--hangups", "1", "--linger-ms", "0"},
                                       (dir.path() + "/emulator.err").toStdString());
    QVERIFY2(pen.firstLine().starts_with("pty: "), pen.firstLine().c_str());
    const QString uri = QStringLiteral("serial://") + QString::fromStdString(pen.firstLine().substr(5));
    QVERIFY2(w.setDevice(uri), qPrintable(w.lastError()));
    QVERIFY(w.rig().active());
    QCOMPARE(w.rig().environment()->limits().degrees_of_freedom, 2);
    QCOMPARE(w.deviceUri(), uri);
    QVERIFY2(w.setDevice("sim://pen?continuous_force_N=1.2"), qPrintable(w.lastError()));
    QCOMPARE(pen.wait(), 0);  // its one hang-up: the free run's
  }

  // A study with no completed trial has nothing to report (one in progress gets the design's
  // analysis of what is done: DesignAnalysis tests it).
  void theReportOfAStudyWithNoTrialIsRefusedWithTheLibrarysMessage() {
    MainWindow& w = window();
    const auto folder = dir_ / "unfinished";
    std::filesystem::create_directories(folder);
    const auto db_file = studio::test::reportStudy(folder, false);
    QVERIFY2(w.openReview(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QList<QUrl> opened;
    w.setUrlOpener([&](const QUrl& url) {
      opened << url;
      return true;
    });
    QVERIFY(!w.openReport());
    QVERIFY2(w.lastError().contains("no trial of the study is completed yet"), qPrintable(w.lastError()));
    QVERIFY(opened.isEmpty());
    QVERIFY(!std::filesystem::exists(reportFolderFor(db_file) / "report.html"));
  }

  void theReportOfAFinishedStudyIsWrittenBesideItAndOpened() {
    MainWindow& w = window();
    const auto folder = dir_ / "finished";
    std::filesystem::create_directories(folder);
    const auto db_file = studio::test::reportStudy(folder, true);
    QVERIFY2(w.openReview(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QList<QUrl> opened;
    w.setUrlOpener([&](const QUrl& url) {
      opened << url;
      return true;
    });
    // No analysis stored: no costs yet, and the tab says how to get them.
    QVERIFY(w.reviewTab()->widgets().costs->text().contains("No analysis is stored"));
    for (const auto& [id, texts] : treeCosts(*w.reviewTab())) QVERIFY(std::get<0>(texts).isEmpty());
    // The report is written off the GUI thread: a 5 ms timer keeps firing meanwhile, the report
    // button is off, and a second report or another study is refused until it is done.
    int ticks = 0;
    bool refused_meanwhile = false;
    QTimer timer;
    timer.setInterval(5);
    QObject::connect(&timer, &QTimer::timeout, [&] {
      ++ticks;
      if (ticks == 2) {
        refused_meanwhile = w.reviewTab()->reporting() && !w.reviewTab()->widgets().report->isEnabled() &&
                            !w.reviewTab()->openReport();
      }
    });
    timer.start();
    QVERIFY2(w.openReport(), qPrintable(w.lastError()));
    timer.stop();
    QVERIFY2(ticks >= 2, qPrintable(QStringLiteral("the GUI thread ran %1 timer ticks while the report was written").arg(ticks)));
    QVERIFY(refused_meanwhile);
    QVERIFY(!w.reviewTab()->reporting());
    QVERIFY(w.reviewTab()->widgets().report->isEnabled());
    // The report's analysis fills the recall trials' costs.
    {
      const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
      expectTreeShows(*w.reviewTab(), report::analyzeStudy(db).costs);
    }
    QVERIFY(w.reviewTab()->widgets().costs->text().contains("report just written"));
    const auto html = folder / "s-report" / "report.html";
    QVERIFY(std::filesystem::exists(html));
    QVERIFY(std::filesystem::file_size(html) > 1000);
    QCOMPARE(opened.size(), 1);
    QCOMPARE(opened.front(), QUrl::fromLocalFile(QString::fromStdString(html.string())));
    // The tables `hattr study report` writes lie beside it, the long table with every trial.
    for (const std::string& name : report::kAnalysisCsvFiles) {
      QVERIFY2(std::filesystem::exists(folder / "s-report" / name), name.c_str());
    }
    const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
    QCOMPARE(io::readTable(folder / "s-report" / "trials.csv").rows.size(), db.trials().size());
  }

  // One learner's study (issue 37): no between-subject statistics, the learner's progress, and
  // every trial's costs in the tree.
  void theReportOfOneLearnersStudyShowsTheirProgress() {
    MainWindow& w = window();
    const auto folder = dir_ / "learner";
    std::filesystem::create_directories(folder);
    const auto db_file = studio::test::reportStudy(folder, true, 1);
    QVERIFY2(w.openReview(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    w.setUrlOpener([](const QUrl&) { return true; });
    QVERIFY2(w.openReport(), qPrintable(w.lastError()));
    const auto md = folder / "s-report" / "report.md";
    QVERIFY(std::filesystem::exists(md));
    std::ifstream in(md);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    QVERIFY2(text.find("One learner practised") != std::string::npos, text.substr(0, 400).c_str());
    QVERIFY(text.find("The learner's progress") != std::string::npos);
    for (const auto& [id, texts] : treeCosts(*w.reviewTab())) QVERIFY(!std::get<0>(texts).isEmpty());
    // The design's tables lie beside it; the long table has every completed trial.
    for (const std::string& name : report::kDesignCsvFiles) {
      QVERIFY2(std::filesystem::exists(folder / "s-report" / name), name.c_str());
    }
    const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
    QCOMPARE(io::readTable(folder / "s-report" / "trials.csv").rows.size(), db.trials().size());
  }

  void theReviewTreeShowsTheStoredAnalysissCostsAndSaysWhenItCannotReadThem() {
    MainWindow& w = window();
    const auto folder = dir_ / "analyzed";
    std::filesystem::create_directories(folder);
    const auto db_file = studio::test::reportStudy(folder, true);
    std::vector<report::TrialCost> costs;
    {
      auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadWrite);
      report::StudyAnalysis analysis = report::analyzeStudy(db);
      analysis.costs.front().disturbed = "1 stall (force zeroed)";  // as a flagged trial's
      report::storeAnalysis(db, analysis);
      costs = analysis.costs;
    }
    QVERIFY2(w.openReview(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    expectTreeShows(*w.reviewTab(), costs);
    QVERIFY(w.reviewTab()->widgets().costs->text().contains("stored analysis"));
    const auto flagged = treeCosts(*w.reviewTab()).at(costs.front().trial_id);
    QVERIFY2(std::get<2>(flagged).endsWith(" disturbed"), qPrintable(std::get<2>(flagged)));

    // A stored analysis the library cannot read: the trials are listed, the tab says why no costs.
    // Opened from the tab itself (its own button's path): the window's buttons follow.
    {
      auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadWrite);
      db.putResult("analysis", "{not json");
    }
    QVERIFY2(w.showReviewTrial(costs.front().trial_id), qPrintable(w.lastError()));
    QVERIFY(w.reviewTab()->widgets().play->isEnabled());
    QVERIFY2(w.reviewTab()->open(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QVERIFY(w.reviewTab()->trial() == nullptr);
    QVERIFY(!w.reviewTab()->widgets().play->isEnabled());  // nothing on show to play
    QVERIFY(w.reviewTab()->widgets().report->isEnabled());
    QVERIFY2(w.reviewTab()->widgets().costs->text().contains("could not be read"),
             qPrintable(w.reviewTab()->widgets().costs->text()));
    const auto shown = treeCosts(*w.reviewTab());
    std::size_t completed = 0;
    {
      const auto db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
      for (const auto& subject : db.subjects()) {
        for (const auto& t : db.trials(subject.id)) completed += t.status == session::TrialStatus::kCompleted ? 1 : 0;
      }
    }
    QCOMPARE(shown.size(), completed);
    for (const auto& [id, texts] : shown) QVERIFY(std::get<0>(texts).isEmpty());
  }

 private:
  MainWindow& window() {
    if (!window_) {
      const QString ini = QString::fromStdString((dir_ / "studio.ini").string());
      window_ = std::make_unique<MainWindow>(std::make_unique<QSettings>(ini, QSettings::IniFormat));
      window_->setInteractive(false);
      window_->resize(1100, 760);
      window_->show();
      (void)QTest::qWaitForWindowExposed(window_.get());
    }
    return *window_;
  }

  std::filesystem::path dir_;
  std::unique_ptr<MainWindow> window_;
};

QTEST_MAIN(StudioInputTest)
#include "studio_input_test.moc"
