// A teacher at the studio (issue 39), on a real X server (Xvfb, Qt's xcb platform), as a
// teacher would use it: Qt Test clicks and typing, no JSON, no terminal. The teacher enrols a
// learner, makes a practice plan for the letter a, runs two sessions with the simulated pen and
// a scripted hand (the mouse moved along the model letter), opens the learner's progress and
// prints it to a file. The screen is read back at 1280 x 800 and 1024 x 680 and checked.
#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QGuiApplication>
#include <QLabel>
#include <QLineEdit>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QScreen>
#include <QSpinBox>
#include <QStatusBar>
#include <QTabBar>
#include <QTabWidget>
#include <QTextBrowser>
#include <QTimer>
#include <QTreeWidget>
#include <QtTest>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/study_session.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/library/profile_library.hpp"
#include "hattr/ops/library.hpp"
#include "hattr/session/study_database.hpp"
#include "library/synthetic_writers.hpp"
#include "screen_checks.hpp"
#include "studio_test_support.hpp"
#include "hattr/sim/glyph.hpp"
#include "ui/learner_dialogs.hpp"
#include "ui/learners_tab.hpp"
#include "ui/library_dialog.hpp"
#include "ui/main_window.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"
#include "ui/progress_curve.hpp"
#include "ui/record_tab.hpp"
#include "ui/review_tab.hpp"
#include "ui/study_tab.hpp"
#include "ui/train_tab.hpp"

using namespace hattr;
using namespace hattr::studio;

#define HATTR_STUDIO_SCREENSHOT_DIR "."

namespace {

/// Types `text` into a line edit as a person does (it is cleared first).
void type(QLineEdit* edit, const QString& text) {
  edit->selectAll();
  QTest::keyClicks(edit, text);
}

/// The modal dialog of `Dialog` open now, once it is.
template <class Dialog>
Dialog* openDialog() {
  Dialog* found = nullptr;
  for (int i = 0; i < 200 && found == nullptr; ++i) {
    found = qobject_cast<Dialog*>(QApplication::activeModalWidget());
    if (found == nullptr) QTest::qWait(10);
  }
  return found;
}

}  // namespace

class StudioTeacherTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    QVERIFY2(QGuiApplication::platformName() == "xcb",
             qPrintable("run under Xvfb with QT_QPA_PLATFORM=xcb (xvfb-run), not on \"" +
                        QGuiApplication::platformName() + "\""));
    dir_ = studio::test::freshTempDir("teacher");
    auto settings =
        std::make_unique<QSettings>(QString::fromStdString((dir_ / "studio.ini").string()), QSettings::IniFormat);
    settings->setValue("train/settle_s", 0.5);
    settings->setValue("input/press_N", 0.8);
    settings->setValue("learners/folder", QString::fromStdString((dir_ / "practice").string()));
    window_ = std::make_unique<MainWindow>(std::move(settings));
    window_->setInteractive(false);
    window_->setUrlOpener([this](const QUrl& url) {
      opened_.push_back(url);
      return true;
    });
    window_->fitToScreen();  // as hattr-studio opens it: nothing remembered yet
    window_->show();
    QVERIFY(QTest::qWaitForWindowExposed(window_.get()));
    window_->fitToScreen();
  }

  void cleanupTestCase() {
    window_.reset();
    std::filesystem::remove_all(dir_);
  }

  // Opened as hattr-studio opens it on the 1280 x 800 screen: within it, the status bar on it
  // (1280 x 820, the size it asks for, would put the status bar off the screen).
  void theFirstWindowFitsTheScreen() {
    MainWindow& w = *window_;
    const QRect screen = w.screen()->availableGeometry();
    QVERIFY2(screen.contains(w.frameGeometry()),
             qPrintable(QString("window %1,%2 %3x%4 on a screen of %5x%6")
                            .arg(w.frameGeometry().x()).arg(w.frameGeometry().y())
                            .arg(w.frameGeometry().width()).arg(w.frameGeometry().height())
                            .arg(screen.width()).arg(screen.height())));
    const QRect status(w.statusBar()->mapToGlobal(QPoint(0, 0)), w.statusBar()->size());
    QVERIFY(w.statusBar()->isVisible() && screen.contains(status));
    w.resize(1280, 800);
  }

  // New learner, then the plan for her: the two forms filled in and accepted with clicks.
  void aTeacherEnrolsALearnerWithAPlanForTheLetterA() {
    MainWindow& w = *window_;
    clickTab(MainWindow::kTabLearners);
    LearnersTab& tab = *w.learnersTab();
    QVERIFY(tab.plans().empty());
    QVERIFY(!tab.widgets().new_plan->isEnabled());  // no learner picked yet

    bool filled_learner = false, filled_plan = false;
    QTimer::singleShot(0, this, [&] {
      auto* dialog = openDialog<LearnerDialog>();
      if (dialog == nullptr) return;
      const auto& f = dialog->widgets();
      type(f.code, "mia");
      type(f.name, "Mia");
      f.age->setValue(7);
      f.handedness->setCurrentIndex(f.handedness->findData(QStringLiteral("left")));
      QTest::keyClicks(f.notes, "Holds the pen very close to the tip");
      filled_learner = true;
      QTimer::singleShot(0, this, [&] {  // the plan's form opens when the learner's closes
        auto* plan = openDialog<PlanDialog>();
        if (plan == nullptr) return;
        const auto& p = plan->widgets();
        // A letter that is not one: the form stays open and says why; then the letter a.
        type(p.letters, "zz");
        QTest::mouseClick(p.buttons->button(QDialogButtonBox::Ok), Qt::LeftButton);
        QVERIFY(plan->isVisible());
        QVERIFY2(p.problems->text().contains("zz") && p.problems->text().contains("not a letter of the library"),
                 qPrintable(p.problems->text()));
        type(p.letters, "a");
        QCOMPARE(p.strategy->currentText(), QStringLiteral("Guided path"));  // plain names
        QVERIFY(p.strategy->itemData(p.strategy->currentIndex(), Qt::ToolTipRole).toString().startsWith("PCONTROL"));
        p.sessions->setValue(2);
        p.trials->setValue(1);
        p.checks->setValue(1);
        p.days_between->setValue(1);
        p.retention_days->setValue(0);
        p.rest_s->setValue(0.5);
        filled_plan = true;
        QTest::mouseClick(p.buttons->button(QDialogButtonBox::Ok), Qt::LeftButton);
      });
      QTest::mouseClick(f.buttons->button(QDialogButtonBox::Ok), Qt::LeftButton);
    });
    QTest::mouseClick(tab.widgets().new_learner, Qt::LeftButton);
    QVERIFY(filled_learner && filled_plan);
    QVERIFY2(w.lastError().isEmpty(), qPrintable(w.lastError()));

    QCOMPARE(tab.plans().size(), std::size_t{1});
    const ops::PracticePlanSummary& plan = tab.plans().front();
    QCOMPARE(plan.learner.name, std::string("Mia"));
    QCOMPARE(plan.learner.age_years, std::optional<int>(7));
    QCOMPARE(plan.learner.handedness, std::string("left"));
    QCOMPARE(plan.letters, std::vector<std::string>{"a"});
    QCOMPARE(plan.trials_total, 5);  // session 1: before practice, guided, alone; session 2: guided, alone
    QVERIFY(tab.selectedPlan() != nullptr);
    QVERIFY(tab.widgets().list->topLevelItem(0)->text(0).startsWith("Mia (mia), 7 years"));
    QVERIFY2(tab.widgets().summary->text().contains("next: session 1 of 2"), qPrintable(tab.widgets().summary->text()));
    plan_file_ = plan.file;
  }

  // Two sessions, the second a day early (the teacher says yes), each trial written by the
  // scripted hand along the model letter and stored as it ends.
  void theLearnerWritesTwoSessions() {
    MainWindow& w = *window_;
    LearnersTab& tab = *w.learnersTab();
    QTest::mouseClick(tab.widgets().continue_plan, Qt::LeftButton);
    QVERIFY2(w.tabs()->currentIndex() == MainWindow::kTabStudy, qPrintable(w.lastError()));
    QVERIFY(w.study() != nullptr);
    QCOMPARE(w.study()->subject(), std::string("mia"));
    const HapticProfile letter = w.study()->expert();
    writeTrials(3, letter);
    QCOMPARE(w.study()->state(), StudySession::State::kNextSession);

    clickTab(MainWindow::kTabLearners);
    QCOMPARE(tab.plans().front().trials_completed, 3);
    // Session 2 is due tomorrow: Continue asks first; no keeps it waiting, yes begins it.
    QTest::mouseClick(tab.widgets().continue_plan, Qt::LeftButton);
    QCOMPARE(w.study()->state(), StudySession::State::kNextSession);
    clickTab(MainWindow::kTabLearners);
    w.setInteractive(false, true);
    QTest::mouseClick(tab.widgets().continue_plan, Qt::LeftButton);
    w.setInteractive(false);
    QVERIFY2(w.tabs()->currentIndex() == MainWindow::kTabStudy, qPrintable(w.lastError()));
    QCOMPARE(w.study()->state(), StudySession::State::kReady);
    writeTrials(2, letter);
    QCOMPARE(w.study()->state(), StudySession::State::kFinished);
    w.closeStudy();

    const auto db = session::StudyDatabase::open(plan_file_, session::OpenMode::kReadOnly);
    for (const auto& t : db.trials("mia")) QCOMPARE(t.status, session::TrialStatus::kCompleted);
  }

  // A library of writers: the teacher picks one's template as the reference (a writer with one
  // recording has none), and asks whose writing the learner's last trial is nearest.
  void aTeacherTrainsAgainstAWritersTemplateFromALibrary() {
    MainWindow& w = *window_;
    const std::string location = makeWriterLibrary();
    QVERIFY(w.lastTrial().has_value());  // the learner's last study trial
    clickTab(MainWindow::kTabTrain);
    bool used = false;
    std::vector<library::RankedPerson> found;
    QTimer::singleShot(0, this, [&] {
      auto* dialog = openDialog<LibraryDialog>();
      if (dialog == nullptr) return;
      // A failed check returns from here: the dialog closes, so exec() returns and the test fails.
      const std::unique_ptr<LibraryDialog, void (*)(LibraryDialog*)> close_unless_used(dialog, [](LibraryDialog* open) {
        if (open->isVisible()) open->reject();
      });
      const auto& d = dialog->widgets();
      QCOMPARE(d.skill->currentText(), QStringLiteral("signature"));
      QCOMPARE(d.persons->topLevelItemCount(), 7);
      QPushButton* ok = d.buttons->button(QDialogButtonBox::Ok);
      QVERIFY(!ok->isEnabled());  // no one chosen
      const auto row = [&](const QString& person) { return d.persons->findItems(person, Qt::MatchExactly, 0).value(0); };
      QVERIFY(row("W7") != nullptr && row("W3") != nullptr);
      QCOMPARE(row("W3")->text(1), QStringLiteral("4"));
      QCOMPARE(row("W3")->text(2), QStringLiteral("1"));  // the imitation of W3
      d.persons->setCurrentItem(row("W7"));
      QVERIFY2(!ok->isEnabled() && ok->toolTip().contains("at least 2 genuine"), qPrintable(ok->toolTip()));
      // The last trial's nearest writers: the exact search's ranks are brute force's.
      QCOMPARE(d.query->currentText(), QStringLiteral("The last trial"));
      QCOMPARE(d.features->currentText(), QStringLiteral("shape+force"));
      d.top->setValue(3);
      QTest::mouseClick(d.find, Qt::LeftButton);
      found = dialog->nearest();
      QCOMPARE(d.nearest->topLevelItemCount(), 3);
      QCOMPARE(d.nearest->topLevelItem(0)->text(1), QString::fromStdString(found.at(0).person));
      screenShotOf(*dialog, "studio_teacher_library.png");
      d.persons->setCurrentItem(row("W3"));
      QVERIFY(ok->isEnabled());
      QCOMPARE(dialog->reference(), QString::fromStdString("library:" + location + "#W3/signature"));
      used = true;
      QTest::mouseClick(ok, Qt::LeftButton);
    });
    QTest::mouseClick(w.trainTab()->widgets().library, Qt::LeftButton);  // asks for the file: none, not interactive
    QVERIFY(!used);
    QVERIFY(w.trainTab()->openLibrary(QString::fromStdString(location)));
    QVERIFY(used);
    ops::IdentifyOptions brute{.skill = "signature", .set = library::parseFeatureSet("shape+force"), .top = 3,
                               .brute_force = true};
    QVERIFY(found == ops::libraryIdentify(location, *w.lastTrial(), brute).ranked);

    // The reference is W3's template of their 4 genuine recordings, named as such.
    const HapticProfile* reference = w.trainTab()->reference();
    QVERIFY(reference != nullptr);
    QCOMPARE(reference->metadata().subject, std::string("W3"));
    const QString label = w.trainTab()->widgets().reference->text();
    QVERIFY2(label.contains("template of <b>W3</b>'s signature") && label.contains("of 4 recordings") &&
                 label.contains("writers.sqlite"),
             qPrintable(label));
    // Not a library: refused, saying what the file is.
    std::ofstream(dir_ / "notes.sqlite") << "not a database";
    QVERIFY(!w.trainTab()->openLibrary(QString::fromStdString((dir_ / "notes.sqlite").string())));
    QVERIFY2(w.lastError().contains("notes.sqlite"), qPrintable(w.lastError()));
    QVERIFY(w.trainTab()->reference() == reference);  // the template stays

    // Remembered: a studio that closes training against the template opens with it again.
    const QString ini = QString::fromStdString((dir_ / "library.ini").string());
    {
      MainWindow other(std::make_unique<QSettings>(ini, QSettings::IniFormat));
      other.setInteractive(false);
      QVERIFY(other.loadReference(QString::fromStdString("library:" + location + "#W3/signature")));
      QVERIFY(other.close());
    }
    MainWindow again(std::make_unique<QSettings>(ini, QSettings::IniFormat));
    QVERIFY2(again.trainTab()->reference() != nullptr, qPrintable(again.lastError()));
    QCOMPARE(again.trainTab()->reference()->metadata().subject, std::string("W3"));
    QVERIFY(again.close());
  }

  // The dialog on its own: a profile file's nearest writer is its own writer.
  void aProfileFilesNearestWriterIsItsOwn() {
    const std::string location =
        std::filesystem::exists(dir_ / "writers.sqlite") ? (dir_ / "writers.sqlite").string() : makeWriterLibrary();
    const auto take = dir_ / "w5-new-take.csv";
    io::writeProfileCsv(hattr::test::syntheticSignature(5, 9), take);
    int asked = 0;
    LibraryDialog dialog(QString::fromStdString(location), nullptr, [&](const QString&, const QString&) {
      ++asked;
      return QString::fromStdString(take.string());
    });
    const auto& d = dialog.widgets();
    QCOMPARE(d.query->count(), 1);  // no last trial to offer
    QVERIFY(dialog.findNearest());
    QCOMPARE(asked, 1);
    QCOMPARE(d.nearest->topLevelItem(0)->text(1), QStringLiteral("W5"));
    QVERIFY(d.problems->isHidden());
    // A feature set the profile lacks: said in the dialog, nothing found.
    io::writeProfileCsv(hattr::test::syntheticSignature(5, 9, 7, false), take, Overwrite::kReplace);
    d.features->setCurrentIndex(d.features->findData(QStringLiteral("angles")));
    QVERIFY(!dialog.findNearest());
    QVERIFY2(!d.problems->isHidden() && d.problems->text().contains("azimuth"), qPrintable(d.problems->text()));
    QCOMPARE(d.nearest->topLevelItemCount(), 0);
  }

  // The progress: a sentence a session, the curve, best and latest; printed to a page.
  void theProgressIsShownAndPrinted() {
    MainWindow& w = *window_;
    clickTab(MainWindow::kTabLearners);
    LearnersTab& tab = *w.learnersTab();
    QVERIFY(tab.progress().has_value());
    const report::LearnerProgress& p = *tab.progress();
    QCOMPARE(p.trials.size(), std::size_t{5});
    QCOMPARE(p.sessions.size(), std::size_t{2});
    QVERIFY2(p.sessions[0].sentence.starts_with("Session 1 (" + p.trials.front().date + "): 1 guided trial and 2 "
                                                "written alone (a); written alone, the shape was"),
             p.sessions[0].sentence.c_str());
    QVERIFY(!p.sessions[1].is_start && std::isfinite(p.sessions[1].change));
    QVERIFY2(p.sessions[1].sentence.find("written alone, the shape was") != std::string::npos,
             p.sessions[1].sentence.c_str());
    int best = 0, latest = 0;
    for (const auto& t : p.trials) {
      best += t.best ? 1 : 0;
      latest += t.latest ? 1 : 0;
      QVERIFY(!(t.guided && (t.best || t.latest)));  // only letters written alone are marked
    }
    QCOMPARE(best, 1);
    QCOMPARE(latest, 1);
    QVERIFY(p.trials.back().latest);
    QCOMPARE(tab.widgets().curve->trials().size(), std::size_t{5});
    const QString shown = tab.widgets().sessions->toPlainText();
    QVERIFY2(shown.contains(QString::fromStdString(p.sessions[1].sentence)), qPrintable(shown));
    QVERIFY(!tab.widgets().continue_plan->isEnabled());  // the plan is done

    const QString page = QString::fromStdString((dir_ / "mia-progress.html").string());
    QVERIFY2(tab.printProgress(page), qPrintable(w.lastError()));
    QCOMPARE(opened_.size(), std::size_t{1});
    QCOMPARE(opened_.back(), QUrl::fromLocalFile(page));
    std::stringstream html;
    html << std::ifstream(page.toStdString()).rdbuf();
    for (const char* expected : {"Progress of Mia (mia)", "age 7 · left-handed", "Holds the pen very close to the tip",
                                 "Session 1 (", "Session 2 (", "★ best", "● latest", "<svg", "Guided path"}) {
      QVERIFY2(html.str().find(expected) != std::string::npos, expected);
    }

    // The Review tab's report of her plan (one learner: no between-subject statistics) opens, and
    // its tree shows every trial's shape and force costs, as the progress has them.
    QVERIFY2(w.openReview(QString::fromStdString(plan_file_.string())), qPrintable(w.lastError()));
    QVERIFY2(w.openReport(), qPrintable(w.lastError()));
    QVERIFY(opened_.back().toLocalFile().endsWith("report.html"));
    QTreeWidget* tree = w.reviewTab()->widgets().tree;
    QCOMPARE(tree->topLevelItemCount(), 1);
    QCOMPARE(tree->topLevelItem(0)->childCount(), 5);
    for (int t = 0; t < 5; ++t) {
      const QString shape = tree->topLevelItem(0)->child(t)->text(ReviewTab::kShape);
      QVERIFY2(std::abs(shape.toDouble() - p.trials[static_cast<std::size_t>(t)].shape) <=
                   1e-3 * p.trials[static_cast<std::size_t>(t)].shape,
               qPrintable(QString("trial %1: tree %2, progress %3").arg(t + 1).arg(shape).arg(p.trials[t].shape)));
    }
  }

  // The Learners tab with the progress, read back from the X server at both sizes: the window
  // did not grow past the screen, the status bar is on it, and the tab's controls, the curve
  // (its points drawn) and the sentences are in view.
  void theProgressFitsBothScreens() {
    for (const QSize size : {QSize(1280, 800), QSize(1024, 680)}) {
      MainWindow& w = *window_;
      w.resize(size);
      clickTab(MainWindow::kTabLearners);
      const QString name = QString("studio_teacher_%1x%2.png").arg(size.width()).arg(size.height());
      const QImage shot = screenShot(name);
      QCOMPARE(w.size(), size);
      QCOMPARE(shot.size(), size);
      const QRect window_rect(QPoint(0, 0), size);
      QVERIFY(w.statusBar()->isVisible());
      QVERIFY2(window_rect.contains(QRect(w.statusBar()->mapTo(&w, QPoint(0, 0)), w.statusBar()->size())),
               qPrintable(name + ": the status bar is cut off"));
      const LearnersTab::Widgets& f = w.learnersTab()->widgets();
      for (QWidget* widget : std::initializer_list<QWidget*>{f.new_learner, f.new_plan, f.continue_plan, f.print, f.list,
                                                              f.curve, f.sessions}) {
        const QRect r(widget->mapTo(&w, QPoint(0, 0)), widget->size());
        QVERIFY2(widget->isVisible() && window_rect.contains(r) && r.height() >= 20,
                 qPrintable(QString("%1: %2 is cut off or hidden").arg(name, widget->objectName())));
      }
      // The curve's dark points (written alone) are on the screen.
      const QRect curve(f.curve->mapTo(&w, QPoint(0, 0)), f.curve->size());
      int dark_points = 0;
      for (int y = curve.top(); y <= curve.bottom(); ++y) {
        for (int x = curve.left(); x <= curve.right(); ++x) {
          dark_points += studio::test::colourNear(shot, QPoint(x, y), QColor(31, 78, 121), 0, 30) ? 1 : 0;
        }
      }
      QVERIFY2(dark_points > 20, qPrintable(QString("%1: %2 pixels of the curve's points").arg(name).arg(dark_points)));
    }
  }

  // Plain by default: the strategies' plain names, the pen's state without the loop's counters,
  // no passivity or deadband. Ctrl+E shows the engineer's view, and it is remembered.
  void thePlainViewSpeaksPlainlyAndTheEngineerViewIsRemembered() {
    MainWindow& w = *window_;
    QVERIFY(!w.engineerView());
    QComboBox* modes = w.trainTab()->widgets().mode;
    const int pcontrol = modes->findData(static_cast<int>(guidance::TrainingMode::kPositionControl));
    QCOMPARE(modes->itemText(pcontrol), QStringLiteral("Guided path"));
    QVERIFY(modes->itemData(pcontrol, Qt::ToolTipRole).toString().startsWith("PCONTROL: "));
    auto* loop = w.findChild<QLabel*>("status_loop");
    QVERIFY(loop != nullptr);
    QTRY_VERIFY2(loop->text().startsWith("Pen: ") && !loop->text().contains("overruns"), qPrintable(loop->text()));
    const MentorTab::Widgets& mentor = w.mentorTab()->widgets();
    QVERIFY(!mentor.passivity->isVisibleTo(w.mentorTab()));
    QVERIFY(!mentor.deadband->isVisibleTo(w.mentorTab()));

    w.activateWindow();  // a shortcut acts in the active window
    QVERIFY(QTest::qWaitForWindowActive(&w));
    QTest::keyClick(&w, Qt::Key_E, Qt::ControlModifier);
    QVERIFY(w.engineerView());
    QCOMPARE(modes->itemText(pcontrol), QStringLiteral("Guided path — PCONTROL"));
    QTRY_VERIFY2(loop->text().startsWith("Loop: ") && loop->text().contains("overruns"), qPrintable(loop->text()));
    QVERIFY(mentor.passivity->isVisibleTo(w.mentorTab()));
    QTest::keyClick(&w, Qt::Key_E, Qt::ControlModifier);
    QVERIFY(!w.engineerView());

    // Remembered: a window that closes in the engineer view opens in it.
    const QString ini = QString::fromStdString((dir_ / "engineer.ini").string());
    {
      MainWindow other(std::make_unique<QSettings>(ini, QSettings::IniFormat));
      other.setInteractive(false);
      QVERIFY(!other.engineerView());
      other.setEngineerView(true);
      QVERIFY(other.close());
    }
    MainWindow again(std::make_unique<QSettings>(ini, QSettings::IniFormat));
    QVERIFY(again.engineerView());
    QCOMPARE(again.trainTab()->widgets().mode->itemText(pcontrol), QStringLiteral("Guided path — PCONTROL"));
    QVERIFY(again.close());
  }

  // The Record tab's letter guide: the letter's strokes on the paper while the tab is shown, the
  // character named after it; none, and the name goes with it.
  void theRecordTabGuidesALetterStrokeByStroke() {
    MainWindow& w = *window_;
    clickTab(MainWindow::kTabRecord);
    RecordTab& record = *w.recordTab();
    QVERIFY(w.paperView()->letterGuide().empty());
    QVERIFY2(record.setLetterGuide("small-a"), qPrintable(w.lastError()));
    const sim::Glyph a = sim::findBuiltInGlyph("a");
    QCOMPARE(w.paperView()->letterGuide().size(), a.strokes.size());
    QCOMPARE(record.widgets().character->text(), QStringLiteral("small-a"));
    QCOMPARE(record.widgets().guide->currentData().toString(), QStringLiteral("small-a"));
    // On the screen: the guide's colour along the letter's via points (its numbered starts and
    // arrowheads cover a few), on the whole paper and four times larger (the Paper box).
    const PaperView* view = w.paperView();
    const double whole_px_per_m = view->mapping().pixelsPerMetre();
    for (const int zoom : {1, 4}) {
      w.zoomBox()->setCurrentIndex(w.zoomBox()->findData(zoom));
      QCOMPARE(view->zoom(), zoom);
      QVERIFY(std::abs(view->mapping().pixelsPerMetre() - zoom * whole_px_per_m) < 1e-6 * whole_px_per_m);
      const QImage shot = screenShot(QString("studio_teacher_record_guide_%1x.png").arg(zoom));
      const QPoint origin = view->mapTo(&w, QPoint(0, 0));
      int points = 0, drawn = 0;
      for (const auto& stroke : a.strokes) {
        for (const auto& p : stroke.points) {
          ++points;
          drawn += studio::test::colourNear(shot, (view->mapping().toWidget(p.x(), p.y()) + QPointF(origin)).toPoint(),
                                    PaperView::guideColour(), 2, 30)
                       ? 1
                       : 0;
        }
      }
      QVERIFY2(drawn >= 0.6 * points,
               qPrintable(QString("zoom %1: %2 of %3 via points in the guide's colour").arg(zoom).arg(drawn).arg(points)));
    }
    clickTab(MainWindow::kTabTrain);
    QVERIFY(w.paperView()->letterGuide().empty());
    clickTab(MainWindow::kTabRecord);
    QCOMPARE(w.paperView()->letterGuide().size(), a.strokes.size());
    QVERIFY(record.setLetterGuide(""));
    QVERIFY(w.paperView()->letterGuide().empty());
    QVERIFY(record.widgets().character->text().isEmpty());
    QVERIFY(!record.setLetterGuide("no-such-letter"));
    QVERIFY2(w.lastError().contains("no-such-letter"), qPrintable(w.lastError()));
    w.zoomBox()->setCurrentIndex(0);  // the whole paper again
  }

  // Guidance past what the pen renders: the arrow stops at the pen's continuous force (10 mm a
  // newton) and the read-out says the help is capped.
  void aGuidanceArrowIsCappedAtWhatThePenRenders() {
    MainWindow& w = *window_;
    clickTab(MainWindow::kTabTrain);
    PaperView* view = w.paperView();
    Sample pen;
    pen.p_WT = Vec3(0.0, 0.0, 0.003);
    pen.f_guide_W = Vec3(9.15, 0.0, 0.0);
    view->setPen(pen);
    QCOMPARE(view->readout(), QStringLiteral("pen 3.0 mm up · pressing 0.0 N · help 1.75 N (the pen's most)"));
    view->setEngineerView(true);
    QVERIFY2(view->readout().contains("guidance 9.15 N (capped at 1.75 N)"), qPrintable(view->readout()));
    view->setEngineerView(false);
    const QImage image = view->grab().toImage();  // painted now, with this pen
    const QPointF at = view->mapping().toWidget(0.0, 0.0);
    const double px_per_mm = view->mapping().pixelsPerMetre() / 1000.0;
    const auto green = [&](double mm) {
      return studio::test::colourNear(image, (at + QPointF(mm * px_per_mm, 0.0)).toPoint(), PaperColours::guideForce(), 1, 40);
    };
    QVERIFY2(green(10.0), "the arrow's shaft 10 mm out");
    QVERIFY2(!green(25.0) && !green(40.0), "the arrow runs past 17.5 mm (1.75 N)");
  }

 private:
  /// `count` study trials: each started with the Study tab's Next, written along `letter`. A
  /// trial the host disturbed (a loaded machine's late ticks) is kept as an attempt and run
  /// again, the plan's "repeat" policy: written again, as a person would, at most twice more.
  void writeTrials(int count, const HapticProfile& letter) {
    MainWindow& w = *window_;
    auto* next = w.findChild<QPushButton*>("study_next");
    QVERIFY(next != nullptr);
    for (int k = 0; k < count; ++k) {
      const int before = w.study()->completedCount();
      QString attempts;
      for (int attempt = 0; attempt < 3 && w.study()->completedCount() == before; ++attempt) {
        QVERIFY(next->isEnabled());
        QTest::mouseClick(next, Qt::LeftButton);
        QCOMPARE(w.activity(), MainWindow::Activity::kStudyTrial);
        studio::test::writeAlong(w, letter, Vec3(0.001, 0.0, 0.0), MainWindow::Activity::kStudyTrial);
        attempts += QString("\n  attempt %1: %2 | %3").arg(attempt + 1).arg(w.statusBar()->currentMessage(),
                                                                            w.studyTab()->scoresLabel()->text());
      }
      QVERIFY2(w.study()->completedCount() == before + 1, qPrintable(w.lastError() + attempts));
    }
  }

  void clickTab(int index) { studio::test::clickTab(*window_, index); }

  /// A library of 6 writers with 4 signatures each, a seventh with one, and an imitation of W3.
  std::string makeWriterLibrary() {
    const std::string location = (dir_ / "writers.sqlite").string();
    auto lib = library::ProfileLibrary::create(location);
    std::vector<std::pair<library::EntryLabels, HapticProfile>> entries;
    const auto add = [&](int writer, int take, library::Authenticity a) {
      library::EntryLabels l;
      l.person = "W" + std::to_string(writer);
      l.key = l.person + "/" + std::to_string(take);
      l.skill = "signature";
      l.authenticity = a;
      entries.emplace_back(l, hattr::test::syntheticSignature(a == library::Authenticity::kGenuine ? writer : 8, take));
    };
    for (int writer = 1; writer <= 6; ++writer) {
      for (int take = 0; take < 4; ++take) add(writer, take, library::Authenticity::kGenuine);
    }
    add(7, 0, library::Authenticity::kGenuine);
    add(3, 4, library::Authenticity::kImitation);
    lib.add(entries);
    return location;
  }

  /// The dialog as the X server shows it, saved in the working folder.
  static void screenShotOf(QWidget& widget, const QString& file) { widget.grab().save(file); }

  QImage screenShot(const QString& file) { return studio::test::screenShot(*window_, file); }

  std::filesystem::path dir_;
  std::filesystem::path plan_file_;
  std::vector<QUrl> opened_;
  std::unique_ptr<MainWindow> window_;
};

QTEST_MAIN(StudioTeacherTest)
#include "studio_teacher_test.moc"
