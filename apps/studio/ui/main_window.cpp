#include "ui/main_window.hpp"

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QCloseEvent>
#include <QComboBox>
#include <QDesktopServices>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QInputDialog>
#include <QLabel>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QSlider>
#include <QSplitter>
#include <QStatusBar>
#include <QTabBar>
#include <QTabWidget>
#include <QTimer>
#include <QToolBar>
#include <QVBoxLayout>
#include <cmath>

#include "core/device_choice.hpp"
#include "core/profile_files.hpp"
#include "hattr/core/error.hpp"
#include "hattr/render/world_config.hpp"
#include "ui/learning_curve.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"
#include "ui/pen_scene_view.hpp"
#include "ui/profile_plot.hpp"
#include "ui/record_tab.hpp"
#include "ui/review_tab.hpp"
#include "ui/study_tab.hpp"
#include "ui/train_tab.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

constexpr int kFramePeriod_ms = 16;  // ~60 Hz display
constexpr int kStatusPeriod_ms = 250;
constexpr double kRollingWindow_s = 5.0;  // the plot's window while writing freely

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
  // The device remembered, else sim://pen (one that no longer validates falls back quietly).
  std::string device_uri = settings_->value("device/uri", QString::fromLatin1(kDefaultDeviceUri)).toString().toStdString();
  try {
    (void)validateStudioDevice(device_uri);
  } catch (const std::exception&) {
    device_uri = kDefaultDeviceUri;
  }
  default_environment_ = std::make_unique<session::TrialEnvironment>(device_uri, world, 1000.0);

  buildUi();
  buildActions();
  loadSettings();
  useEnvironment(*default_environment_);

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
  // Every tab's name in view: without scroll arrows (a small window hid the last tabs behind
  // them) the tab bar's minimum is the whole bar, and so the panel's, whatever the font.
  tabs_->tabBar()->setUsesScrollButtons(false);
  connect(tabs_, &QTabWidget::currentChanged, this, [this] { refreshButtons(); });

  splitter_ = new QSplitter(Qt::Horizontal);
  splitter_->addWidget(left_splitter_);
  splitter_->addWidget(tabs_);
  splitter_->setStretchFactor(0, 3);
  splitter_->setStretchFactor(1, 1);
  setCentralWidget(splitter_);

  // Tool bar: how hard the hand presses, the force arrows.
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

  // Status bar: the input, the loop, the activity; always visible.
  status_input_ = new QLabel;
  status_loop_ = new QLabel;
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

// The Record tab records on the window's rig, paper and plot (RecordHost).
void MainWindow::buildRecordTab() {
  RecordHost host;
  host.idle = [this] { return activity_ == Activity::kFree || activity_ == Activity::kPlayback; };
  host.recording = [this] { return activity_ == Activity::kRecording; };
  host.begin = [this](const RunSpec& spec) {
    if (activity_ == Activity::kPlayback) abortActivity();
    playback_.load(nullptr);
    try {
      rig_.start(*environment_, spec, hand_, session::Clock::kRealTime);
    } catch (...) {
      startFreeRun();
      throw;
    }
    activity_ = Activity::kRecording;
    paper_->trail().clear();
    paper_->overlay().clear();
    plot_->trainee().clear();
    plot_->setCursorTime(std::nullopt);
    plot_->setTitle(tr("Recording"));
  };
  host.end = [this] {
    session::TrialResult result = rig_.finish();
    activity_ = Activity::kFree;
    startFreeRun();
    return result;
  };
  host.show = [this](const HapticProfile& take) {
    paper_->trail().assign(take);
    plot_->setTrainee(ForceSeries::fromProfile(take));
    plot_->setExpert({});
    plot_->setTimeWindow(std::nullopt);
    plot_->setTitle(tr("Take"));
    plot_holds_result_ = true;
  };
  host.play = [this](const HapticProfile& take) { startPlayback(&take, nullptr); };
  host.use_as_reference = [this](const HapticProfile& take) {
    if (!train_tab_->useTake(take, takeName())) return false;
    tabs_->setCurrentIndex(kTabTrain);
    return true;
  };
  host.take_changed = [this] {
    if (record_tab_->take()) {
      train_tab_->takeRenamed(takeName());
    } else {
      train_tab_->takeGone();
    }
  };
  host.save = [this](const HapticProfile& profile, const QString& file, bool& saved) {
    return saveProfileTo(profile, file, saved);
  };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.confirm = [this](const QString& question) { return confirm(question); };
  host.ask_save_file = [this](const QString& title, const QString& name) { return askSaveFile(title, name); };
  host.changed = [this] { refreshButtons(); };
  record_tab_ = new RecordTab(rig_, *settings_, std::move(host));
  tabs_->addTab(record_tab_, tr("Record"));
}

// The Train tab runs its trials on the window's rig, paper and plot (TrainHost).
void MainWindow::buildTrainTab() {
  TrainHost host;
  host.idle = [this] { return activity_ == Activity::kFree || activity_ == Activity::kPlayback; };
  host.trial_running = [this] { return activity_ == Activity::kTrial; };
  host.may_change_reference = [this] { return activity_ != Activity::kTrial && activity_ != Activity::kStudyTrial; };
  host.rate_hz = [this] { return environment_->rate_hz(); };
  host.start_trial = [this](const session::TrialSetup& setup, const HapticProfile& expert, bool reference_on_paper,
                            const QString& title, QLabel* scores) {
    beginLiveTrial(*environment_, setup, Activity::kTrial, expert, reference_on_paper, true, title, scores);
  };
  host.stop_trial = [this] { (void)stopTrial(); };
  host.switch_mode = [this](guidance::TrainingMode mode) { return rig_.switchMode(mode); };
  host.show_reference = [this](const HapticProfile& reference, bool shown) {
    if (activity_ != Activity::kFree && activity_ != Activity::kRecording) return;  // a trial or session has the views
    showReference(&reference);
    paper_->setReferenceShown(shown);
    // The new reference alone on the plot: the last take's curves go; it stays until the pen writes.
    plot_->setTrainee({});
    plot_->setCursorTime(std::nullopt);
    plot_->setTimeWindow(std::nullopt);
    plot_->setTitle(tr("Reference"));
    plot_holds_result_ = true;
    plot_->setExpert(ForceSeries::fromProfile(reference, 4000, -reference.samples().front().t_s));
  };
  host.reference_shown = [this](bool shown) {
    if (activity_ != Activity::kStudyTrial) paper_->setReferenceShown(shown);
  };
  host.has_last_trial = [this] { return last_trial_.has_value(); };
  host.replay_last_trial = [this] {
    if (last_trial_) startPlayback(&*last_trial_, last_trial_expert_ ? &*last_trial_expert_ : nullptr);
  };
  host.save_last_trial = [this] {
    if (!last_trial_) return;
    const QString file = askSaveFile(tr("Save the trial as a haptic profile"), QStringLiteral("trial.csv"));
    if (!file.isEmpty()) saveLastTrial(file);
  };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.ask_open_file = [this](const QString& title, const QString& filter) { return askOpenFile(title, filter); };
  host.changed = [this] { refreshButtons(); };
  train_tab_ = new TrainTab(*settings_, std::move(host));
  tabs_->addTab(train_tab_, tr("Train"));
}

// The Study tab runs its trials on the window's rig, paper and plot (StudyHost).
void MainWindow::buildStudyTab() {
  StudyHost host;
  host.idle = [this] { return activity_ == Activity::kFree || activity_ == Activity::kPlayback; };
  host.trial_running = [this] { return activity_ == Activity::kStudyTrial; };
  host.device_busy = [this] { return activity_ == Activity::kStudyTrial || activity_ == Activity::kMentoring; };
  host.clear_views = [this] {
    if (activity_ == Activity::kPlayback) abortActivity();
    paper_->overlay().clear();
    paper_->trail().clear();
    plot_->clear();
  };
  host.use_environment = [this](session::TrialEnvironment* environment) {
    (void)rig_.finish();  // the loop runs on the paper that may go
    if (environment == nullptr) {
      showReference(train_tab_->reference());
      paper_->setReferenceShown(train_tab_->referenceShown());
    }
    useEnvironment(environment != nullptr ? *environment : *default_environment_);
  };
  host.show_reference = [this](const HapticProfile* expert, bool shown) {
    showReference(expert);
    paper_->setReferenceShown(shown);
  };
  host.hide_reference = [this] {
    paper_->setReferenceShown(false);
    plot_->setExpert(ForceSeries{});
  };
  host.start_trial = [this](session::TrialEnvironment& environment, const session::TrialSetup& setup,
                            const HapticProfile& expert, bool shows_reference, const QString& title, QLabel* scores) {
    beginLiveTrial(environment, setup, Activity::kStudyTrial, expert, shows_reference, shows_reference, title, scores);
  };
  host.stop_trial = [this] { (void)stopTrial(); };
  host.settle_s = [this] { return train_tab_->settle_s(); };
  host.now_s = [this] { return now_s(); };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.confirm = [this](const QString& question) { return confirm(question); };
  host.ask_open_file = [this](const QString& title, const QString& filter) { return askOpenFile(title, filter); };
  host.note = [this](const QString& message, int ms) { statusBar()->showMessage(message, ms); };
  host.changed = [this] { refreshButtons(); };
  study_tab_ = new StudyTab(*settings_, std::move(host));
  tabs_->addTab(study_tab_, tr("Study"));
}

void MainWindow::buildReviewTab() {
  ReviewHost host;
  host.may_show = [this] { return activity_ == Activity::kFree || activity_ == Activity::kPlayback; };
  host.show = [this](const HapticProfile& trial, const HapticProfile& expert, const QString& title, QLabel* scores) {
    showReviewed(trial, expert, title, scores);
  };
  host.forget = [this](const HapticProfile* shown) {
    if (activity_ == Activity::kPlayback) abortActivity();
    if (shown != nullptr && playback_.profile() == shown) playback_.load(nullptr);
    paper_->overlay().clear();
  };
  host.toggle_playback = [this] { togglePlayback(); };
  host.set_speed = [this](double speed) { playback_.setSpeed(speed); };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.ask_open_file = [this](const QString& title, const QString& filter) { return askOpenFile(title, filter); };
  host.note = [this](const QString& message) { statusBar()->showMessage(message, 10000); };
  host.open_url = [this](const QUrl& url) { return !url_opener_ || url_opener_(url); };
  host.changed = [this] { refreshButtons(); };
  review_ = new ReviewTab(*settings_, std::move(host));
  tabs_->addTab(review_, tr("Review"));
}

// The Mentor tab borrows the device (the rig stops; Activity::kMentoring) and the dialogs.
void MainWindow::buildMentorTab() {
  MentorHost host;
  host.claim = [this](QString& why) -> const session::TrialEnvironment* {
    if (activity_ == Activity::kPlayback) abortActivity();
    if (activity_ != Activity::kFree) {
      why = tr("finish the trial or recording first");
      return nullptr;
    }
    (void)rig_.finish();
    activity_ = Activity::kMentoring;
    paper_->overlay().clear();
    refreshButtons();
    return environment_;
  };
  host.release = [this] {
    activity_ = Activity::kFree;
    startFreeRun();
    refreshButtons();
  };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.confirm = [this](const QString& question) { return confirm(question); };
  host.ask_save_file = [this](const QString& title, const QString& name) { return askSaveFile(title, name); };
  host.ask_open_file = [this](const QString& title, const QString& filter) { return askOpenFile(title, filter); };
  mentor_ = new MentorTab(hand_, *paper_, *settings_, std::move(host));
  tabs_->addTab(mentor_, tr("Mentor"));
}

void MainWindow::buildActions() {
  const auto add = [this](QMenu* menu, const QString& text, const QKeySequence& keys, auto slot) {
    auto* action = new QAction(text, this);
    action->setShortcut(keys);
    action->setShortcutContext(Qt::WindowShortcut);
    connect(action, &QAction::triggered, this, slot);
    menu->addAction(action);
    addAction(action);
    return action;
  };
  QMenu* file = menuBar()->addMenu(tr("&File"));
  add(file, tr("Open reference…"), QKeySequence(Qt::CTRL | Qt::Key_O), [this] {
    const QString f = askOpenFile(tr("Open a reference profile"), tr("Haptic profiles (*.csv);;All files (*)"));
    if (!f.isEmpty()) loadReference(f);
  });
  add(file, tr("Load world…"), QKeySequence(Qt::CTRL | Qt::Key_W), [this] {
    const QString f = askOpenFile(tr("Load a world configuration"), tr("World configuration (*.json);;All files (*)"));
    if (!f.isEmpty()) loadWorld(f);
  });
  add(file, tr("Open study…"), QKeySequence(Qt::CTRL | Qt::Key_D), [this] {
    const QString f = askOpenFile(tr("Open a study database"), tr("Study databases (*.sqlite *.db);;All files (*)"));
    if (!f.isEmpty()) openStudy(f);
  });
  add(file, tr("Open study for review…"), QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_D), [this] {
    const QString f =
        askOpenFile(tr("Open a study database for review"), tr("Study databases (*.sqlite *.db);;All files (*)"));
    if (!f.isEmpty()) openReview(f);
  });
  add(file, tr("Open report…"), QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_R), [this] { (void)openReport(); });
  file->addSeparator();
  add(file, tr("Device…"), QKeySequence(), [this] { askDevice(); });
  add(file, tr("Tablet calibration…"), QKeySequence(), [this] {
    const QString f = askOpenFile(tr("Load a tablet calibration"), tr("Tablet calibration (*.json);;All files (*)"));
    if (!f.isEmpty()) loadTabletCalibration(f);
  });
  file->addSeparator();
  add(file, tr("Save take…"), QKeySequence(Qt::CTRL | Qt::Key_S), [this] { record_tab_->askSave(); });
  add(file, tr("Save last trial…"), QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S),
      [this] { train_tab_->widgets().save->click(); });
  file->addSeparator();
  add(file, tr("Quit"), QKeySequence(Qt::CTRL | Qt::Key_Q), [this] { close(); });

  QMenu* act = menuBar()->addMenu(tr("&Actions"));
  add(act, tr("Start / stop (the tab's main action)"), QKeySequence(Qt::Key_Space), [this] { primaryAction(); });
  add(act, tr("Stop trial (keep it)"), QKeySequence(Qt::CTRL | Qt::Key_Period), [this] { stopTrial(); });
  add(act, tr("Abort trial, recording or playback (nothing kept)"), QKeySequence(Qt::Key_Escape),
      [this] { abortActivity(); });
  add(act, tr("Record / stop recording"), QKeySequence(Qt::Key_R), [this] {
    tabs_->setCurrentIndex(kTabRecord);
    record_tab_->toggle();
  });
  add(act, tr("Start trial"), QKeySequence(Qt::Key_T), [this] {
    tabs_->setCurrentIndex(kTabTrain);
    if (activity_ != Activity::kTrial) startTrial();
  });
  add(act, tr("Next (study: skip the rest, start the trial)"), QKeySequence(Qt::Key_N), [this] { studyNext(); });
  add(act, tr("Play / pause"), QKeySequence(Qt::Key_P), [this] { togglePlayback(); });
  add(act, tr("Clear trail"), QKeySequence(Qt::Key_C), [this] { clearTrail(); });
  act->addSeparator();
  add(act, tr("Mode BASIC"), QKeySequence(Qt::Key_1), [this] { setMode(guidance::TrainingMode::kBasic); });
  add(act, tr("Mode PCONTROL"), QKeySequence(Qt::Key_2), [this] { setMode(guidance::TrainingMode::kPositionControl); });
  add(act, tr("Mode ALPHA"), QKeySequence(Qt::Key_3), [this] { setMode(guidance::TrainingMode::kForceControl); });
  act->addSeparator();
  add(act, tr("Press harder"), QKeySequence(Qt::Key_Plus),
      [this] { press_slider_->setValue(press_slider_->value() + 1); });
  add(act, tr("Press lighter"), QKeySequence(Qt::Key_Minus),
      [this] { press_slider_->setValue(press_slider_->value() - 1); });
  QMenu* view = menuBar()->addMenu(tr("&View"));
  for (int tab = 0; tab < tabs_->count(); ++tab) {
    add(view, tabs_->tabText(tab), QKeySequence(Qt::CTRL | static_cast<Qt::Key>(Qt::Key_1 + tab)),
        [this, tab] { tabs_->setCurrentIndex(tab); });
  }
  QMenu* help = menuBar()->addMenu(tr("&Help"));
  add(help, tr("Shortcuts"), QKeySequence(Qt::Key_F1), [this] {
    QMessageBox::information(
        this, tr("hattr studio: shortcuts"),
        tr("<table>"
           "<tr><td><b>Space</b></td><td>the tab's main action: record/stop, start/stop trial, study next, "
           "play/pause, connect/disconnect (Mentor)</td></tr>"
           "<tr><td><b>Ctrl+.</b></td><td>stop the trial now and keep it (end reason \"stopped\"; a study "
           "stores it); stop a recording</td></tr>"
           "<tr><td><b>Esc</b></td><td>abort the trial, recording or playback (nothing kept)</td></tr>"
           "<tr><td><b>R</b></td><td>record / stop recording</td></tr>"
           "<tr><td><b>T</b></td><td>start a training trial</td></tr>"
           "<tr><td><b>N</b></td><td>study: skip the rest / start the next trial</td></tr>"
           "<tr><td><b>P</b></td><td>play / pause the take, trial or reviewed trial</td></tr>"
           "<tr><td><b>1 2 3</b></td><td>BASIC, PCONTROL, ALPHA</td></tr>"
           "<tr><td><b>+ −</b>, wheel</td><td>press harder / lighter</td></tr>"
           "<tr><td><b>C</b></td><td>clear the trail</td></tr>"
           "<tr><td><b>Ctrl+O</b></td><td>open a reference</td></tr>"
           "<tr><td><b>Ctrl+S</b>, <b>Ctrl+Shift+S</b></td><td>save the take, save the last trial</td></tr>"
           "<tr><td><b>Ctrl+D</b>, <b>Ctrl+Shift+D</b></td><td>open a study, open a study for review</td></tr>"
           "<tr><td><b>Ctrl+W</b></td><td>load a world configuration</td></tr>"
           "<tr><td><b>Ctrl+Shift+R</b></td><td>review: open the study's report</td></tr>"
           "<tr><td><b>Ctrl+1…6</b></td><td>the tabs</td></tr>"
           "</table>"));
  });
}

// ---- Settings ------------------------------------------------------------------------------

void MainWindow::setSceneShown(bool shown) { scene_check_->setChecked(shown); }

void MainWindow::loadSettings() {
  QSettings& s = *settings_;
  restoreGeometry(s.value("window/geometry").toByteArray());
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
  // The reference of last time, quietly: a file that went away just leaves none loaded.
  const QString reference = s.value("train/reference_file").toString();
  if (!reference.isEmpty() && QFileInfo::exists(reference)) {
    const bool was = interactive_;
    interactive_ = false;
    loadReference(reference);
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
  s.setValue("view/scene_3d", scene_check_->isChecked());
  s.setValue("window/view_splitter", view_splitter_->saveState());
  record_tab_->saveSettings();
  train_tab_->saveSettings();
  s.setValue("world/file", world_file_);
  s.sync();
}

void MainWindow::closeEvent(QCloseEvent* event) {
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

// ---- Dialogs -------------------------------------------------------------------------------

void MainWindow::setInteractive(bool interactive, bool answer) {
  interactive_ = interactive;
  answer_ = answer;
}

void MainWindow::showError(const QString& what, const QString& detail) {
  last_error_ = what + QStringLiteral(": ") + detail;
  statusBar()->showMessage(last_error_, 10000);
  if (interactive_)
    QMessageBox::critical(this, tr("hattr studio"),
                          QStringLiteral("<b>%1</b><br><br>%2").arg(what.toHtmlEscaped(), detail.toHtmlEscaped()));
}

bool MainWindow::confirm(const QString& question) {
  if (!interactive_) return answer_;
  return QMessageBox::question(this, tr("hattr studio"), question, QMessageBox::Yes | QMessageBox::No,
                               QMessageBox::No) == QMessageBox::Yes;
}

QString MainWindow::askSaveFile(const QString& title, const QString& suggested) {
  if (!interactive_) return {};
  const QString dir = settings_->value("files/last_dir").toString();
  const QString file =
      QFileDialog::getSaveFileName(this, title, dir.isEmpty() ? suggested : dir + "/" + suggested,
                                   tr("Haptic profiles (*.csv)"), nullptr, QFileDialog::DontConfirmOverwrite);
  if (!file.isEmpty()) settings_->setValue("files/last_dir", QFileInfo(file).absolutePath());
  return file;
}

QString MainWindow::askOpenFile(const QString& title, const QString& filter) {
  if (!interactive_) return {};
  const QString file = QFileDialog::getOpenFileName(this, title, settings_->value("files/last_dir").toString(), filter);
  if (!file.isEmpty()) settings_->setValue("files/last_dir", QFileInfo(file).absolutePath());
  return file;
}

void MainWindow::askDevice() {
  if (!interactive_) return;
  bool ok = false;
  const QString uri = QInputDialog::getText(
      this, tr("Device"),
      tr("The device, by URI. The mouse or tablet holds a simulated pen (sim://pen, plugin:sim, or one served "
         "over udp://); a hardware pen (plugin:, udp://) is held by the person.\n\n%1")
          .arg(qs(device::deviceUriHelp())),
      QLineEdit::Normal, deviceUri(), &ok);
  if (ok && !uri.trimmed().isEmpty()) (void)setDevice(uri.trimmed());
}

// ---- The live rig and the display -----------------------------------------------------------

void MainWindow::useEnvironment(session::TrialEnvironment& environment) {
  environment_ = &environment;
  const DeviceLimits& limits = environment.limits();
  paper_->setPaper(environment.paper().relief(), limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                   limits.workspace_max_m.x(), limits.workspace_max_m.y());
  scene_->setPaper(environment.paper().relief(), limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                   limits.workspace_max_m.x(), limits.workspace_max_m.y());
  QString clamps;
  for (const auto& line : environment.worldClamps()) clamps += QStringLiteral("<br>· ") + qs(line).toHtmlEscaped();
  world_label_->setText(tr("Device <tt>%1</tt> at %2 Hz; world: %3%4")
                            .arg(qs(environment.deviceUri()).toHtmlEscaped())
                            .arg(environment.rate_hz())
                            .arg(world_file_.isEmpty() ? tr("defaults") : world_file_.toHtmlEscaped())
                            .arg(clamps.isEmpty() ? QString() : tr("<br>Clamped to the device:%1").arg(clamps)));
  startFreeRun();
}

void MainWindow::startFreeRun() {
  RunSpec spec;
  spec.metadata.subject = "studio";
  try {
    rig_.start(*environment_, spec, hand_, session::Clock::kRealTime);
  } catch (const std::exception& e) {
    showError(tr("The servo loop could not start"), QString::fromUtf8(e.what()));
  }
  if (activity_ != Activity::kPlayback) activity_ = Activity::kFree;
}

void MainWindow::consumeLive(const Sample& sample) {
  switch (activity_) {
    case Activity::kTrial:
    case Activity::kStudyTrial: {
      const double t_trial = sample.t_s - rig_.spec().settle_s;
      if (t_trial < 0.0 || t_trial > rig_.spec().duration_s) return;
      paper_->trail().append(sample);
      plot_->trainee().append(t_trial, sample.f_user_W);
      return;
    }
    case Activity::kFree:
    case Activity::kRecording: {
      paper_->trail().append(sample);
      // A trial or take stays on the plot until the pen writes again.
      if (plot_holds_result_) {
        if (!sample.pen_down) return;
        plot_holds_result_ = false;
        plot_->clear();
        plot_->setTitle(tr("Live"));
      }
      ForceSeries& series = plot_->trainee();
      series.append(sample.t_s, sample.f_user_W);
      // Keep the last few seconds.
      std::size_t old = 0;
      while (old < series.size() && series.t_s[old] < sample.t_s - kRollingWindow_s) ++old;
      if (old > 64) {
        for (auto* v : {&series.t_s, &series.fx_N, &series.fy_N, &series.fz_N})
          v->erase(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(old));
      }
      plot_->setTimeWindow(std::make_pair(sample.t_s - kRollingWindow_s, sample.t_s));
      return;
    }
    case Activity::kPlayback:
    case Activity::kMentoring: return;
  }
}

void MainWindow::onFrame() {
  // A mentoring session has the device: the Mentor tab draws both pens.
  if (activity_ == Activity::kMentoring) {
    mentor_->frame();
    paper_->update();
    return;
  }
  const double now = now_s();
  Sample sample;
  const bool fresh = rig_.active() && rig_.readLatest(sample);
  if (fresh) latest_ = sample;
  const RigStatus status = rig_.status();
  if (activity_ != Activity::kPlayback) paper_->setPen(rig_.active() ? std::optional<Sample>(latest_) : std::nullopt);
  if (fresh) consumeLive(latest_);

  QString banner;
  switch (activity_) {
    case Activity::kTrial:
    case Activity::kStudyTrial: {
      // The reference's point now (as the guidance played it, time or progress indexing), the
      // countdown, the end.
      const double t_trial = status.loop_time_s - rig_.spec().settle_s;
      std::optional<Vec3> cue = rig_.referenceCue();
      if (!cue && status.settling && rig_.spec().reference) cue = rig_.spec().reference->at(0.0).p_WT;  // the start
      paper_->setReferenceCue(cue ? std::optional<Eigen::Vector2d>(cue->head<2>()) : std::nullopt);
      const double left_s = std::max(0.0, rig_.spec().duration_s - t_trial);
      if (status.settling) {
        banner = tr("Get ready: %1 s").arg(std::max(0.0, -t_trial), 0, 'f', 1);
      } else if (rig_.spec().pen_up_end_s > 0.0) {
        banner = tr("Write! Lift the pen when you are done (%1 s left)").arg(left_s, 0, 'f', 1);
      } else {
        banner = tr("Write! %1 s").arg(left_s, 0, 'f', 1);
      }
      // The trial is over: the pen lifted long enough (the end rule) or the maximum passed.
      if (status.window_done || status.writing_over) finishTrial();
      break;
    }
    case Activity::kRecording: banner = record_tab_->recordingBanner(); break;
    case Activity::kPlayback: {
      const double t = playback_.time_s(now);
      const std::size_t i = playback_.indexAt(t);
      const HapticProfile& p = *playback_.profile();
      paper_->trail().assign(p, 0, i + 1);
      paper_->setPen(p[i]);
      plot_->setCursorTime(t);
      banner = tr("Playback %1 / %2 s").arg(t, 0, 'f', 2).arg(p.samples().back().t_s, 0, 'f', 2);
      if (playback_.playing() && playback_.finished(now)) playback_.pause(now);
      break;
    }
    case Activity::kMentoring: break;  // drawn by the Mentor tab (above)
    case Activity::kFree:
      banner = study_tab_->idleBanner();  // a study's rest, prompt or thanks
      break;
  }
  paper_->setBanner(banner);
  paper_->update();
  plot_->update();
}

void MainWindow::onStatus() {
  const double now = now_s();
  // The input.
  const MouseInput& input = hand_.input();
  status_input_->setText(tr("Input: %1 (%2, %3) mm · %4 · press %5 N")
                             .arg(input.tablet ? tr("tablet") : tr("mouse"))
                             .arg(input.x_m * 1000.0, 0, 'f', 1)
                             .arg(input.y_m * 1000.0, 0, 'f', 1)
                             .arg(input.pen_down ? tr("pen down") : tr("pen up"))
                             .arg(input.tablet ? input.tablet_press_N : input.press_N, 0, 'f', 1));
  // The loop: measured rate, overruns, faults, drops, stalls.
  const bool mentoring = activity_ == Activity::kMentoring;
  const servo::LiveCounters* counters = mentoring ? mentor_->counters() : rig_.counters();
  if (counters == nullptr) {
    status_loop_->setText(tr("Loop: stopped"));
  } else {
    const std::uint64_t ticks = counters->ticks.load();
    if (ticks >= last_ticks_ && now > last_status_s_) {
      loop_rate_hz_ = static_cast<double>(ticks - last_ticks_) / (now - last_status_s_);
    }
    last_ticks_ = ticks;
    status_loop_->setText(tr("Loop: %1 Hz · overruns %2 · faults %3 · drops %4 · stalls %5 · %6")
                              .arg(loop_rate_hz_, 0, 'f', 0)
                              .arg(counters->overruns.load())
                              .arg(counters->faults.load())
                              .arg(counters->dropped_samples.load())
                              .arg(counters->stalls.load() + counters->consumer_stalls.load())
                              .arg(mentoring ? tr("mentoring station") : qs(rig_.realtimeSummary())));
  }
  last_status_s_ = now;
  static const char* kNames[] = {"writing", "recording", "training trial", "study trial", "playback", "mentoring"};
  // The mode the loop runs: a study trial's own (a recall trial is BASIC whatever its mode),
  // otherwise the Train tab's.
  const guidance::TrainingMode shown = activity_ == Activity::kStudyTrial ? rig_.spec().guidance.mode : train_tab_->mode();
  status_activity_->setText(tr("Activity: %1 · mode %2")
                                .arg(QString::fromLatin1(kNames[static_cast<int>(activity_)]))
                                .arg(qs(std::string(guidance::modeName(shown)))));
}

void MainWindow::refreshButtons() {
  record_tab_->refresh();
  train_tab_->refresh();
  study_tab_->refresh();
  review_->refresh(playback_.loaded());
}

void MainWindow::showReference(const HapticProfile* expert) {
  paper_->reference().clear();
  if (expert != nullptr) paper_->reference().assign(*expert);
  paper_->setReferenceCue(std::nullopt);
}

}  // namespace hattr::studio
