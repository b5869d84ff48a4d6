// The main window's tabs (each a controller/view pair lent the rig, the paper and the plot
// through its host), its menus and its keys.
#include "ui/main_window.hpp"

#include <QAction>
#include <QApplication>
#include <QFileDialog>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QSlider>
#include <QStatusBar>
#include <QTabWidget>

#include "core/study_session.hpp"
#include "ui/learners_tab.hpp"
#include "ui/learning_curve.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"
#include "ui/profile_plot.hpp"
#include "ui/record_tab.hpp"
#include "ui/review_tab.hpp"
#include "ui/study_tab.hpp"
#include "ui/train_tab.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

// An action in `menu` and on `window` (so its shortcut works anywhere in the window) that
// calls `slot`.
template <class Slot>
QAction* addMenuAction(MainWindow* window, QMenu* menu, const QString& text, const QKeySequence& keys, Slot slot) {
  auto* action = new QAction(text, window);
  action->setShortcut(keys);
  action->setShortcutContext(Qt::WindowShortcut);
  QObject::connect(action, &QAction::triggered, window, slot);
  menu->addAction(action);
  window->addAction(action);
  return action;
}

}  // namespace

// The Record tab records on the window's rig, paper and plot (RecordHost).
void MainWindow::buildRecordTab() {
  RecordHost host;
  host.idle = [this] { return idle(); };
  host.recording = [this] { return activity_ == Activity::kRecording; };
  host.begin = [this](const RunSpec& spec) {
    startRun(*environment_, spec, Activity::kRecording);
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
  // The guide is on the paper while the Record tab is (buildUi switches it with the tabs).
  host.show_guide = [this](const std::vector<std::vector<Eigen::Vector2d>>& strokes_m) {
    if (tabs_->currentIndex() == kTabRecord) paper_->setLetterGuide(strokes_m);
  };
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
  host.idle = [this] { return idle(); };
  host.trial_running = [this] { return activity_ == Activity::kTrial; };
  host.may_change_reference = [this] { return activity_ != Activity::kTrial && activity_ != Activity::kStudyTrial; };
  // Before the first environment is in use (settings loading), the default one's rate.
  host.rate_hz = [this] { return (environment_ != nullptr ? environment_ : default_environment_.get())->rate_hz(); };
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
  host.last_trial = [this]() -> const HapticProfile* { return last_trial_ ? &*last_trial_ : nullptr; };
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
  host.idle = [this] { return idle(); };
  host.trial_running = [this] { return activity_ == Activity::kStudyTrial; };
  host.device_busy = [this] { return !idle(); };
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
    startFreeRunOn(environment != nullptr ? *environment : *default_environment_);
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
  host.may_show = [this] { return idle(); };
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

// The Learners tab makes plans and shows progress; Continue runs a plan in the Study tab.
void MainWindow::buildLearnersTab() {
  LearnersHost host;
  host.continue_plan = [this](const QString& file, const QString& learner) { return continuePlan(file, learner); };
  host.error = [this](const QString& what, const QString& detail) { showError(what, detail); };
  host.ask_save_file = [this](const QString& title, const QString& suggested) -> QString {
    if (!interactive_) return {};
    return QFileDialog::getSaveFileName(this, title, suggested, tr("Web page (*.html)"));
  };
  host.ask_folder = [this](const QString& title, const QString& start) -> QString {
    if (!interactive_) return {};
    return QFileDialog::getExistingDirectory(this, title, start);
  };
  host.open_url = [this](const QUrl& url) { return !url_opener_ || url_opener_(url); };
  host.note = [this](const QString& message, int ms) { statusBar()->showMessage(message, ms); };
  learners_tab_ = new LearnersTab(*settings_, std::move(host));
  tabs_->addTab(learners_tab_, tr("Learners"));
}

bool MainWindow::continuePlan(const QString& file, const QString& learner) {
  if (!idle()) {
    showError(tr("The plan cannot continue now"), tr("finish the trial, recording or session that runs first"));
    return false;
  }
  // The plan open in the Study tab already goes on where it is (opening it again would wait on
  // its own runner lock).
  const bool open = study() != nullptr && study()->file() == std::filesystem::path(file.toStdString());
  if (open) {
    tabs_->setCurrentIndex(kTabStudy);
  } else if (!openStudy(file)) {
    return false;
  }
  if (study()->subject() != learner.toStdString() && !selectStudySubject(learner)) return false;
  if (study()->state() == StudySession::State::kNextSession) return studyNext();
  return true;
}

void MainWindow::buildActions() {
  buildFileMenu();
  buildActionsMenu();
  buildViewMenu();
  buildHelpMenu();
}

// File: references, worlds, studies, the report, the device, saving, quitting.
void MainWindow::buildFileMenu() {
  const auto add = [this](QMenu* menu, const QString& text, const QKeySequence& keys, auto slot) {
    return addMenuAction(this, menu, text, keys, slot);
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
}

// Actions: the tab's main action, trials, recording, playback, the modes, the press force.
void MainWindow::buildActionsMenu() {
  const auto add = [this](QMenu* menu, const QString& text, const QKeySequence& keys, auto slot) {
    return addMenuAction(this, menu, text, keys, slot);
  };
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
}

// View: a shortcut per tab (Ctrl+1…).
void MainWindow::buildViewMenu() {
  QMenu* view = menuBar()->addMenu(tr("&View"));
  for (int tab = 0; tab < tabs_->count(); ++tab) {
    addMenuAction(this, view, tabs_->tabText(tab), QKeySequence(Qt::CTRL | static_cast<Qt::Key>(Qt::Key_1 + tab)),
                  [this, tab] { tabs_->setCurrentIndex(tab); });
  }
  view->addSeparator();
  engineer_action_ = addMenuAction(this, view, tr("Engineer view"), QKeySequence(Qt::CTRL | Qt::Key_E),
                                   [this](bool checked) { setEngineerView(checked); });
  engineer_action_->setCheckable(true);
  engineer_action_->setToolTip(tr("The loop's counters, DTW units, technical strategy names, the mentoring "
                                   "station's passivity and deadband"));
}

// Help: the table of shortcuts.
void MainWindow::buildHelpMenu() {
  QMenu* help = menuBar()->addMenu(tr("&Help"));
  addMenuAction(this, help, tr("Shortcuts"), QKeySequence(Qt::Key_F1), [this] {
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
           "<tr><td><b>Ctrl+1…7</b></td><td>the tabs</td></tr>"
           "<tr><td><b>Ctrl+E</b></td><td>the engineer view (on / off)</td></tr>"
           "</table>"));
  });
}


}  // namespace hattr::studio
