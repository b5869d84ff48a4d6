// The studio on a real X server (Xvfb, through Qt's xcb platform), at the 1024 × 680 a lab's
// small screen gives it: each tab is clicked on its tab bar (QTest::mouseClick), and the screen
// itself is read back from the X server (not the widgets' own rendering) and saved as
// studio_screen_<tab>.png in the build folder. Each shot is checked for its content: the
// window's pixels on the screen are the widgets' pixels, the Train tab shows the expert's
// reference, the Study tab a banner that fits its box with white text in it, the Review tab
// the reviewed trial in its colour.
#include <QGuiApplication>
#include <QHeaderView>
#include <QScreen>
#include <QScrollBar>
#include <QTabBar>
#include <QTabWidget>
#include <QTreeWidget>
#include <QtTest>
#include <algorithm>
#include <fstream>

#include "hattr/io/profile_csv.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study_database.hpp"
#include "screen_checks.hpp"
#include "studio_test_support.hpp"
#include "ui/main_window.hpp"
#include "ui/paper_view.hpp"
#include "ui/pen_scene_view.hpp"
#include "ui/review_tab.hpp"

using namespace hattr;
using namespace hattr::studio;
using test::shareDrawn;

// Screenshots are kept in the working folder: ctest runs the test in its build folder.
#define HATTR_STUDIO_SCREENSHOT_DIR "."

namespace {

constexpr QSize kSmallScreenWindow(1024, 680);

/// The share of `region`'s pixels (window coordinates) that are the same in both images
/// (each channel within 8: the X server may dither nothing, but a repaint may move a cursor).
double shareAlike(const QImage& a, const QImage& b, const QRect& region) {
  const QImage ca = a.convertToFormat(QImage::Format_RGB32), cb = b.convertToFormat(QImage::Format_RGB32);
  long alike = 0, total = 0;
  for (int y = region.top(); y <= region.bottom(); ++y) {
    for (int x = region.left(); x <= region.right(); ++x) {
      if (!ca.rect().contains(x, y) || !cb.rect().contains(x, y)) continue;
      const QRgb p = ca.pixel(x, y), q = cb.pixel(x, y);
      ++total;
      alike += std::abs(qRed(p) - qRed(q)) <= 8 && std::abs(qGreen(p) - qGreen(q)) <= 8 &&
                       std::abs(qBlue(p) - qBlue(q)) <= 8
                   ? 1
                   : 0;
    }
  }
  return total == 0 ? 0.0 : static_cast<double>(alike) / static_cast<double>(total);
}

/// The share of `region`'s pixels for which `test(colour)` holds.
template <typename Test>
double shareOf(const QImage& image, const QRect& region, Test test) {
  long count = 0, total = 0;
  for (int y = region.top(); y <= region.bottom(); ++y) {
    for (int x = region.left(); x <= region.right(); ++x) {
      if (!image.rect().contains(x, y)) continue;
      ++total;
      count += test(image.pixelColor(x, y)) ? 1 : 0;
    }
  }
  return total == 0 ? 0.0 : static_cast<double>(count) / static_cast<double>(total);
}

bool light(const QColor& c) { return std::min({c.red(), c.green(), c.blue()}) > 150; }
bool whiteText(const QColor& c) { return std::min({c.red(), c.green(), c.blue()}) > 225; }
bool dark(const QColor& c) { return std::max({c.red(), c.green(), c.blue()}) < 110; }

}  // namespace

class StudioScreenTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    // On a screen, not offscreen: this test is about what an X server shows.
    QVERIFY2(QGuiApplication::platformName() == "xcb",
             qPrintable("run under Xvfb with QT_QPA_PLATFORM=xcb (xvfb-run), not on \"" +
                        QGuiApplication::platformName() + "\""));
    dir_ = test::freshTempDir("screen");
    session::TrialEnvironment flat("sim://pen", test::flatWorld(), 1000.0);
    expert_ = test::recordExpert(flat);
    expert_file_ = dir_ / "expert.csv";
    io::writeProfileCsv(expert_, expert_file_);
    review_dir_ = dir_ / "review";
    std::filesystem::create_directories(review_dir_);
    review_db_ = test::reportStudy(review_dir_, true);
    {
      auto db = session::StudyDatabase::open(review_db_, session::OpenMode::kReadWrite);
      report::storeAnalysis(db, report::analyzeStudy(db));  // as `hattr study analyze` leaves it
    }

    auto settings =
        std::make_unique<QSettings>(QString::fromStdString((dir_ / "studio.ini").string()), QSettings::IniFormat);
    settings->setValue("train/settle_s", 0.5);
    window_ = std::make_unique<MainWindow>(std::move(settings));
    window_->setInteractive(false);
    window_->resize(kSmallScreenWindow);
    window_->show();
    QVERIFY(QTest::qWaitForWindowExposed(window_.get()));
  }

  void cleanupTestCase() {
    window_.reset();
    std::filesystem::remove_all(dir_);
  }

  // Every tab, clicked on the tab bar: it is the current one, and the screen shows the
  // window as its widgets draw it (the page and the paper view), not a blank or stale one.
  void eachTabIsClickedAndShownOnTheScreen() {
    MainWindow& w = *window_;
    // The window fits the small screen with every tab in view.
    qInfo("the window's smallest width: %d px", w.minimumSizeHint().width());
    QVERIFY(w.minimumSizeHint().width() <= kSmallScreenWindow.width());
    QCOMPARE(w.size(), kSmallScreenWindow);
    QTabBar* bar = w.tabs()->tabBar();
    for (int k = 0; k < w.tabs()->count(); ++k) {
      // Every tab's name is in view, none behind scroll arrows.
      QVERIFY2(bar->rect().contains(bar->tabRect(k)) && bar->width() <= w.tabs()->width(),
               qPrintable(w.tabs()->tabText(k) + " is not in view on the tab bar"));
    }
    for (int k = 0; k < w.tabs()->count(); ++k) {
      const QString name = w.tabs()->tabText(k).remove('&').toLower();
      QTest::mouseClick(bar, Qt::LeftButton, Qt::NoModifier, bar->tabRect(k).center());
      QTRY_COMPARE(w.tabs()->currentIndex(), k);
      const QImage screen = screenShot("studio_screen_" + name + ".png");
      const QImage drawn = w.grab().toImage();
      QCOMPARE(screen.size(), drawn.size());
      const QWidget* page = w.tabs()->currentWidget();
      const QRect page_rect(page->mapTo(&w, QPoint(0, 0)), page->size());
      const double page_alike = shareAlike(screen, drawn, page_rect);
      QVERIFY2(page_alike > 0.99, qPrintable(QString("%1: %2 of the page's pixels on the screen are the widgets'")
                                                  .arg(name)
                                                  .arg(page_alike)));
      // The page has something on it: text and controls, not one flat colour.
      const QColor background = screen.pixelColor(page_rect.topLeft() + QPoint(2, 2));
      const double flat = shareOf(screen, page_rect, [&](const QColor& c) { return c == background; });
      QVERIFY2(flat < 0.98, qPrintable(name + ": the page is blank"));
      // The paper is on the screen: light (its grain too) over most of the paper's rectangle,
      // where the desk around it is dark.
      const PaperView* view = w.paperView();
      const QRectF paper = view->mapping().paperRectPx().translated(view->mapTo(&w, QPoint(0, 0)));
      const double paper_light = shareOf(screen, paper.toAlignedRect().adjusted(40, 40, -40, -40), light);
      QVERIFY2(paper_light > 0.9, qPrintable(QString("%1: %2 of the paper light on the screen").arg(name).arg(paper_light)));
    }
  }

  // The 3-D view beside the paper still fits the small screen, and the X server shows it:
  // the lit paper (light) in the paper's far left quarter (away from the pen), the desk (dark)
  // in a corner.
  void theThreeDViewFitsBesideThePaperOnTheScreen() {
    MainWindow& w = *window_;
    w.setSceneShown(true);
    const PenSceneView* scene = w.sceneView();
    QVERIFY(scene->isVisible());
    const QImage screen = screenShot("studio_screen_3d.png");  // after the layout took the view in
    qInfo("the window's smallest width with the 3-D view: %d px", w.minimumSizeHint().width());
    QVERIFY(w.minimumSizeHint().width() <= kSmallScreenWindow.width());
    QCOMPARE(screen.size(), kSmallScreenWindow);  // the window did not grow to show it
    const Eigen::Vector2d quarter = scene->camera().toPixels(Vec3(-0.04, 0.03, 0.0));
    const QPoint at = scene->mapTo(&w, QPoint(static_cast<int>(quarter.x()), static_cast<int>(quarter.y())));
    const double paper_light = shareOf(screen, QRect(at - QPoint(6, 6), QSize(13, 13)), light);
    QVERIFY2(paper_light > 0.9, qPrintable(QString("%1 of the 3-D paper light on the screen").arg(paper_light)));
    const QPoint corner = scene->mapTo(&w, QPoint(scene->width() - 6, scene->height() - 6));
    QVERIFY(dark(screen.pixelColor(corner)));
    w.setSceneShown(false);
  }

  // Train: the expert's reference, in its colour, where the reference lies.
  void theTrainTabShowsTheReference() {
    MainWindow& w = *window_;
    QVERIFY2(w.loadReference(QString::fromStdString(expert_file_.string())), qPrintable(w.lastError()));
    clickTab(MainWindow::kTabTrain);
    const QImage screen = screenShot("studio_screen_train_reference.png");
    const double drawn = shareDrawn(screen, w, expert_, PaperColours::reference());
    QVERIFY2(drawn > 0.9, qPrintable(QString("%1 of the reference's points drawn on the screen").arg(drawn)));
  }

  // Study: the prompt's banner fits its box at this size, and its text is on the screen.
  void theStudyBannerIsReadableInASmallWindow() {
    MainWindow& w = *window_;
    std::ofstream(dir_ / "study.json") << test::smallStudyJson(
        "[\"pcontrol\", \"alpha\"]", 1.0, "[{\"id\": \"P01\", \"participant\": \"person\"}]", "flat");
    const auto db_file = dir_ / "study.sqlite";
    { (void)session::StudyDatabase::create(db_file, session::loadStudy(dir_ / "study.json")); }
    QVERIFY2(w.openStudy(QString::fromStdString(db_file.string())), qPrintable(w.lastError()));
    QVERIFY2(w.selectStudySubject("P01"), qPrintable(w.lastError()));
    clickTab(MainWindow::kTabStudy);
    const PaperView* view = w.paperView();
    QTRY_VERIFY(view->banner().contains("Space to start"));
    const PaperView::BannerLayout banner = view->bannerLayout();
    QVERIFY2(banner.fits, qPrintable("the banner does not fit its box: " + view->banner()));
    const QImage screen = screenShot("studio_screen_study.png");
    const QRect box = banner.box.translated(view->mapTo(&w, QPoint(0, 0))).toAlignedRect().adjusted(4, 4, -4, -4);
    // The box is dark over the light paper, its text white: both on the screen.
    const double white = shareOf(screen, box, whiteText), box_dark = shareOf(screen, box, dark);
    QVERIFY2(white > 0.03, qPrintable(QString("%1 of the banner white text").arg(white)));
    QVERIFY2(box_dark > 0.5, qPrintable(QString("%1 of the banner dark").arg(box_dark)));
    w.closeStudy();
  }

  // Review: the chosen trial over the expert, in the reviewed trial's colour.
  void theReviewTabShowsTheReviewedTrial() {
    MainWindow& w = *window_;
    QVERIFY2(w.openReview(QString::fromStdString(review_db_.string())), qPrintable(w.lastError()));
    const auto db = session::StudyDatabase::open(review_db_, session::OpenMode::kReadOnly);
    const auto trials = db.trials(db.subjects().front().id);
    const session::TrialRecord& last = trials.back();
    QVERIFY2(w.showReviewTrial(last.id), qPrintable(w.lastError()));
    clickTab(MainWindow::kTabReview);
    const QImage screen = screenShot("studio_screen_review.png");
    const double drawn = shareDrawn(screen, w, db.trialProfile(last.id), PaperColours::overlay(), 2);
    QVERIFY2(drawn > 0.8, qPrintable(QString("%1 of the reviewed trial's points drawn on the screen").arg(drawn)));
    // The tree's costs are in view in the narrow panel, numbers in them, without scrolling.
    QTreeWidget* tree = w.reviewTab()->widgets().tree;
    QCOMPARE(tree->horizontalScrollBar()->value(), 0);
    for (const int column : {ReviewTab::kShape, ReviewTab::kForce}) {
      const int right = tree->header()->sectionViewportPosition(column) + tree->header()->sectionSize(column);
      QVERIFY2(right <= tree->viewport()->width(),
               qPrintable(QString("column %1 ends at %2 px, the tree shows %3").arg(column).arg(right).arg(tree->viewport()->width())));
    }
    int with_costs = 0;
    for (int t = 0; t < tree->topLevelItem(0)->childCount(); ++t) {
      with_costs += tree->topLevelItem(0)->child(t)->text(ReviewTab::kShape).isEmpty() ? 0 : 1;
    }
    QCOMPARE(with_costs, 6);  // 2 analyzed recall trials (the first of each mode is not) × 3 modes
  }

 private:
  void clickTab(int index) { test::clickTab(*window_, index); }

  QImage screenShot(const QString& file) { return test::screenShot(*window_, file); }

  std::filesystem::path dir_;
  std::filesystem::path expert_file_;
  std::filesystem::path review_dir_;
  std::filesystem::path review_db_;
  HapticProfile expert_;
  std::unique_ptr<MainWindow> window_;
};

QTEST_MAIN(StudioScreenTest)
#include "studio_screen_test.moc"
