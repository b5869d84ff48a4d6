// The main window: its construction (the views, the tool bar, the Write tab), its settings and closing.
#include "ui/main_window.hpp"

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QCloseEvent>
#include <QComboBox>
#include <QDesktopServices>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QLabel>
#include <QMenuBar>
#include <QPushButton>
#include <QScreen>
#include <QSlider>
#include <QSplitter>
#include <QStatusBar>
#include <QTabBar>
#include <QTabWidget>
#include <QTimer>
#include <QToolBar>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>

#include "core/device_choice.hpp"
#include "core/window_fit.hpp"
#include "hattr/library/profile_template.hpp"
#include "hattr/render/world_config.hpp"
#include "ui/learning_curve.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"
#include "ui/pen_scene_view.hpp"
#include "ui/profile_plot.hpp"
#include "ui/record_tab.hpp"
#include "ui/review_tab.hpp"
#include "ui/train_tab.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

constexpr int kFramePeriod_ms = 16;  // ~60 Hz display
constexpr int kStatusPeriod_ms = 250;

}  // namespace

MainWindow::MainWindow(std::unique_ptr<QSettings> settings, QWidget* parent)
    : QMainWindow(parent), settings_(std::move(settings)) {
  if (!settings_) settings_ = std::make_unique<QSettings>(QStringLiteral("hattr"), QStringLiteral("studio"));
  clock_.start();
  setWindowTitle(tr("hattr studio"));
  url_opener_ = [](const QUrl& url) { return QDesktopServices::openUrl(url); };

  // The default paper: the world file remembered, else the defaults.
  world_file_ = settings_->value("world/file").toString();
  render::WorldConfig world;
  if (!world_file_.isEmpty()) {
    try {
      world = render::loadWorldConfig(world_file_.toStdString());
    } catch (const std::exception&) {
      world_file_.clear();  // a world file that went bad: fall back to the defaults silently
    }
  }
  // The device remembered, else sim://pen: one whose URI no longer parses, or that does not open
  // for the first free run, falls back quietly (nothing is opened just to ask it).
  const std::string device_uri =
      settings_->value("device/uri", QString::fromLatin1(kDefaultDeviceUri)).toString().toStdString();
  try {
    default_environment_ = std::make_unique<session::TrialEnvironment>(device_uri, world, 1000.0);
  } catch (const std::exception&) {
    default_environment_ = std::make_unique<session::TrialEnvironment>(kDefaultDeviceUri, world, 1000.0);
  }

  buildUi();
  buildActions();
  loadSettings();
  QString failed = useEnvironment(*default_environment_);
  if (!failed.isEmpty() && default_environment_->deviceUri() != kDefaultDeviceUri) {
    default_environment_ = std::make_unique<session::TrialEnvironment>(kDefaultDeviceUri, world, 1000.0);
    failed = useEnvironment(*default_environment_);
  }
  if (!failed.isEmpty()) showError(tr("The servo loop could not start"), failed);

  frame_timer_ = new QTimer(this);
  frame_timer_->setTimerType(Qt::PreciseTimer);
  connect(frame_timer_, &QTimer::timeout, this, &MainWindow::onFrame);
  frame_timer_->start(kFramePeriod_ms);
  status_timer_ = new QTimer(this);
  connect(status_timer_, &QTimer::timeout, this, &MainWindow::onStatus);
  status_timer_->start(kStatusPeriod_ms);
  refreshButtons();
}

MainWindow::~MainWindow() {
  mentor_->shutdown();  // its session uses the hand, which goes before the tab does
  (void)rig_.finish();
}

double MainWindow::now_s() const { return static_cast<double>(clock_.nsecsElapsed()) * 1e-9; }

// ---- Construction ------------------------------------------------------------------------

void MainWindow::buildUi() {
  paper_ = new PaperView;
  paper_->setMouseHand(&hand_);
  plot_ = new ProfilePlot;
  // The top view, and beside it the 3-D view (hidden until asked for).
  scene_ = new PenSceneView(paper_);
  scene_->hide();
  view_splitter_ = new QSplitter(Qt::Horizontal);
  view_splitter_->setChildrenCollapsible(false);
  view_splitter_->addWidget(paper_);
  view_splitter_->addWidget(scene_);
  left_splitter_ = new QSplitter(Qt::Vertical);
  left_splitter_->addWidget(view_splitter_);
  left_splitter_->addWidget(plot_);
  left_splitter_->setStretchFactor(0, 3);
  left_splitter_->setStretchFactor(1, 1);

  tabs_ = new QTabWidget;
  buildWriteTab();
  buildRecordTab();
  buildTrainTab();
  buildStudyTab();
  buildReviewTab();
  buildMentorTab();
  buildLearnersTab();
  // Every tab's name in view: without scroll arrows (a small window hid the last tabs behind
  // them) the tab bar's minimum is the whole bar, and so the panel's, whatever the font.
  tabs_->tabBar()->setUsesScrollButtons(false);
  connect(tabs_, &QTabWidget::currentChanged, this, [this](int tab) {
    // The Record tab's letter guide is on the paper while that tab is.
    paper_->setLetterGuide(tab == kTabRecord ? record_tab_->guideStrokes() : std::vector<std::vector<Eigen::Vector2d>>{});
    refreshButtons();
  });

  splitter_ = new QSplitter(Qt::Horizontal);
  splitter_->addWidget(left_splitter_);
  splitter_->addWidget(tabs_);
  splitter_->setStretchFactor(0, 3);
  splitter_->setStretchFactor(1, 1);
  setCentralWidget(splitter_);

  // Tool bar: how hard the hand presses, the force arrows.
  buildToolBar();

  // Status bar: the input, the loop, the activity; always visible.
  buildStatusBar();
}

// Tool bar: how hard the hand presses, the force arrows, the 3-D view.
void MainWindow::buildToolBar() {
  auto* tools = addToolBar(tr("Input"));
  tools->setObjectName("input_toolbar");
  tools->addWidget(new QLabel(tr(" Press ")));
  press_slider_ = new QSlider(Qt::Horizontal);
  press_slider_->setRange(PressScale::toSliderSteps(PressScale::kMin_N), PressScale::toSliderSteps(PressScale::kMax_N));
  press_slider_->setFixedWidth(160);
  press_slider_->setToolTip(
      tr("How hard the hand presses the pen along its axis while the left button is held "
         "(also the mouse wheel over the paper)"));
  tools->addWidget(press_slider_);
  press_label_ = new QLabel;
  press_label_->setMinimumWidth(60);
  tools->addWidget(press_label_);
  connect(press_slider_, &QSlider::valueChanged, this, [this](int steps) {
    MouseInput input = hand_.input();
    input.press_N = PressScale::fromSliderSteps(steps);
    hand_.setInput(input);
    press_label_->setText(tr("%1 N").arg(input.press_N, 0, 'f', 1));
  });
  connect(paper_, &PaperView::pressChanged, this, [this](double press_N) {
    const QSignalBlocker block(press_slider_);
    press_slider_->setValue(PressScale::toSliderSteps(press_N));
    press_label_->setText(tr("%1 N").arg(press_N, 0, 'f', 1));
  });
  tools->addSeparator();
  // How much of the paper the top view shows (letters are 10 to 20 mm tall).
  tools->addWidget(new QLabel(tr(" Paper ")));
  zoom_box_ = new QComboBox;
  zoom_box_->setObjectName("paper_zoom");
  zoom_box_->addItem(tr("whole"), 1);
  for (int k = 2; k <= PaperView::kMaxZoom; ++k) zoom_box_->addItem(tr("%1×").arg(k), k);
  zoom_box_->setToolTip(tr("Show the whole paper, or its middle larger: for letters (the hand's strokes get finer too)"));
  connect(zoom_box_, &QComboBox::currentIndexChanged, this,
          [this](int index) { paper_->setZoom(zoom_box_->itemData(index).toInt()); });
  tools->addWidget(zoom_box_);
  tools->addSeparator();
  arrows_check_ = new QCheckBox(tr("Force arrows"));
  arrows_check_->setChecked(true);
  connect(arrows_check_, &QCheckBox::toggled, this, [this](bool on) { paper_->setForceArrowsShown(on); });
  tools->addWidget(arrows_check_);
  scene_check_ = new QCheckBox(tr("3-D view"));
  scene_check_->setToolTip(tr("The pen over the paper in 3-D, with its tilt, beside the top view"));
  connect(scene_check_, &QCheckBox::toggled, this, [this](bool on) {
    scene_->setVisible(on);
    // Shown: two fifths of the room beside the paper (the top view keeps its minimum).
    const int room = view_splitter_->width();
    if (on) view_splitter_->setSizes({room - room * 2 / 5, room * 2 / 5});
  });
  tools->addWidget(scene_check_);
}

// Status bar: the input, the loop, the activity; always visible.
void MainWindow::buildStatusBar() {
  status_input_ = new QLabel;
  status_loop_ = new QLabel;
  status_loop_->setObjectName("status_loop");
  status_activity_ = new QLabel;
  status_activity_->setObjectName("status_activity");
  statusBar()->addWidget(status_activity_, 1);
  statusBar()->addPermanentWidget(status_input_);
  statusBar()->addPermanentWidget(status_loop_);
}

void MainWindow::buildWriteTab() {
  auto* page = new QWidget;
  auto* layout = new QVBoxLayout(page);
  layout->addWidget(wrappedLabel(
      tr("<b>Write</b> on the virtual paper with the simulated force-feedback pen. The mouse is your hand: "
         "move it over the paper to move the pen, hold the <b>left button</b> to put the pen down, turn the "
         "<b>wheel</b> (or use the Press slider) to press harder or lighter.")));
  world_label_ = wrappedLabel();
  layout->addWidget(world_label_);
  auto* load_world = new QPushButton(tr("Load world…"));
  connect(load_world, &QPushButton::clicked, this, [this] {
    const QString file =
        askOpenFile(tr("Load a world configuration"), tr("World configuration (*.json);;All files (*)"));
    if (!file.isEmpty()) loadWorld(file);
  });
  auto* clear = new QPushButton(tr("Clear trail (C)"));
  connect(clear, &QPushButton::clicked, this, &MainWindow::clearTrail);
  auto* device = new QPushButton(tr("Device…"));
  device->setToolTip(tr("The device by URI: sim://pen?continuous_force_N=1.2, plugin:NAME, udp://HOST:PORT?key=FILE, ..."));
  connect(device, &QPushButton::clicked, this, &MainWindow::askDevice);
  auto* calibration = new QPushButton(tr("Tablet calibration…"));
  calibration->setToolTip(tr("A pen tablet's pressure → force calibration (JSON, as `hattr import --calibration`)"));
  connect(calibration, &QPushButton::clicked, this, [this] {
    const QString f = askOpenFile(tr("Load a tablet calibration"), tr("Tablet calibration (*.json);;All files (*)"));
    if (!f.isEmpty()) loadTabletCalibration(f);
  });
  layout->addWidget(load_world);
  layout->addWidget(device);
  layout->addWidget(calibration);
  layout->addWidget(clear);
  layout->addStretch(1);
  tabs_->addTab(page, tr("Write"));
}

// ---- Settings ------------------------------------------------------------------------------

void MainWindow::setSceneShown(bool shown) { scene_check_->setChecked(shown); }

void MainWindow::fitToScreen() {
  const QScreen* on = screen();
  if (on == nullptr) return;
  const QRect available = on->availableGeometry();
  // The frame is known once the window is shown; before, allow a title bar's and borders' room.
  const QSize frame = isVisible() ? frameGeometry().size() - geometry().size() : QSize(8, 40);
  const QSize wanted = geometry_restored_ || isVisible() ? size() : kPreferredWindowSize;
  resize(fitWindow(wanted, available.size(), frame, minimumSizeHint()));
  // Onto the screen, its frame too.
  const QRect frame_rect(frameGeometry().topLeft(), size() + frame);
  QPoint at = frame_rect.topLeft();
  at.setX(std::clamp(at.x(), available.left(), std::max(available.left(), available.right() - frame_rect.width() + 1)));
  at.setY(std::clamp(at.y(), available.top(), std::max(available.top(), available.bottom() - frame_rect.height() + 1)));
  if (at != frame_rect.topLeft()) move(at);
}

void MainWindow::loadSettings() {
  QSettings& s = *settings_;
  geometry_restored_ = restoreGeometry(s.value("window/geometry").toByteArray());
  restoreState(s.value("window/state").toByteArray());
  splitter_->restoreState(s.value("window/splitter").toByteArray());
  left_splitter_->restoreState(s.value("window/left_splitter").toByteArray());
  view_splitter_->restoreState(s.value("window/view_splitter").toByteArray());
  tabs_->setCurrentIndex(s.value("window/tab", 0).toInt());
  const double press_N = s.value("input/press_N", PressScale::kDefault_N).toDouble();
  press_slider_->setValue(PressScale::toSliderSteps(press_N));
  MouseInput input = hand_.input();
  input.press_N = PressScale::fromSliderSteps(press_slider_->value());
  hand_.setInput(input);
  press_label_->setText(tr("%1 N").arg(input.press_N, 0, 'f', 1));
  arrows_check_->setChecked(s.value("view/arrows", true).toBool());
  zoom_box_->setCurrentIndex(std::max(0, zoom_box_->findData(s.value("view/zoom", 1).toInt())));
  setEngineerView(s.value("view/engineer", false).toBool());
  scene_check_->setChecked(s.value("view/scene_3d", false).toBool());
  // The tablet calibration of last time, quietly (a file that went bad: the defaults).
  const QString calibration = s.value("input/tablet_calibration").toString();
  if (!calibration.isEmpty() && QFileInfo::exists(calibration)) {
    const bool was = interactive_;
    interactive_ = false;
    loadTabletCalibration(calibration);
    interactive_ = was;
    last_error_.clear();
  }
  // The reference of last time, quietly: a file that went away (or a letter no longer built
  // in) just leaves none loaded. A library template is tried whenever it was one (its library
  // may be a database, or have lost the person: then none is loaded either).
  const QString reference = s.value("train/reference_file").toString();
  const QString letter = s.value("train/reference_letter").toString();
  const bool file_there = !reference.isEmpty() && (QFileInfo::exists(reference) ||
                                                   library::isLibraryReference(reference.toStdString()));
  if (file_there || !letter.isEmpty()) {
    const bool was = interactive_;
    interactive_ = false;
    if (file_there) {
      loadReference(reference);
    } else {
      train_tab_->useLetter(letter);
    }
    interactive_ = was;
    last_error_.clear();
  }
}

void MainWindow::saveSettings() {
  QSettings& s = *settings_;
  s.setValue("window/geometry", saveGeometry());
  s.setValue("window/state", saveState());
  s.setValue("window/splitter", splitter_->saveState());
  s.setValue("window/left_splitter", left_splitter_->saveState());
  s.setValue("window/tab", tabs_->currentIndex());
  s.setValue("input/press_N", hand_.input().press_N);
  s.setValue("view/arrows", arrows_check_->isChecked());
  s.setValue("view/zoom", paper_->zoom());
  s.setValue("view/scene_3d", scene_check_->isChecked());
  s.setValue("view/engineer", engineer_view_);
  s.setValue("window/view_splitter", view_splitter_->saveState());
  record_tab_->saveSettings();
  train_tab_->saveSettings();
  s.setValue("world/file", world_file_);
  s.sync();
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (review_->reporting()) {  // its worker writes into the study's report folder
    showError(tr("The studio cannot close now"), tr("a report is being written; close it when the report is done"));
    event->ignore();
    return;
  }
  if (!record_tab_->mayClose()) {
    event->ignore();
    return;
  }
  if (last_trial_ && !last_trial_saved_ && !confirm(tr("The last trial was not stored anywhere. Quit and lose it?"))) {
    event->ignore();
    return;
  }
  if (!mentor_->mayClose()) {
    event->ignore();
    return;
  }
  saveSettings();
  (void)rig_.finish();
  event->accept();
}

}  // namespace hattr::studio
