// The main window's actions: record, train, the trials it runs for the Study tab, review, playback.
#include <fmt/format.h>

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileInfo>
#include <QLabel>
#include <QApplication>
#include <QDir>
#include <QLineEdit>
#include <QPushButton>
#include <QStatusBar>
#include <QTabWidget>

#include "core/device_choice.hpp"
#include "core/profile_files.hpp"
#include "core/tablet_input.hpp"
#include "hattr/core/error.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/trial_physics.hpp"
#include "ui/learning_curve.hpp"
#include "ui/main_window.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"
#include "ui/profile_plot.hpp"
#include "ui/record_tab.hpp"
#include "ui/review_tab.hpp"
#include "ui/study_tab.hpp"
#include "ui/train_tab.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

// ---- Train --------------------------------------------------------------------------------

bool MainWindow::loadReference(const QString& file) { return train_tab_->loadReference(file); }

bool MainWindow::useTakeAsReference() { return record_tab_->useAsReference(); }

TakeName MainWindow::takeName() const {
  return {.file = record_tab_->takeFile(), .expert = record_tab_->expertName(), .character = record_tab_->character()};
}

guidance::TrainingMode MainWindow::mode() const { return train_tab_->mode(); }

LearningCurve* MainWindow::learningCurve() const { return train_tab_->learningCurve(); }

bool MainWindow::loadWorld(const QString& file) {
  if (!idle()) {
    showError(tr("The world cannot change now"), tr("finish the trial or recording first"));
    return false;
  }
  try {
    auto environment = std::make_unique<session::TrialEnvironment>(default_environment_->deviceUri(),
                                                                   render::loadWorldConfig(file.toStdString()),
                                                                   default_environment_->rate_hz());
    // The rig runs on the default paper unless a study is open (then the study's stays).
    const bool in_use = study() == nullptr;
    if (in_use) (void)rig_.finish();
    default_environment_ = std::move(environment);
    world_file_ = file;
    if (in_use) startFreeRunOn(*default_environment_);
    return true;
  } catch (const std::exception& e) {
    showError(tr("The world configuration could not be loaded"), what(e));
    return false;
  }
}

bool MainWindow::setDevice(const QString& uri) {
  if (!idle()) {
    showError(tr("The device cannot change now"), tr("finish the trial or recording first"));
    return false;
  }
  try {
    // Nothing is opened to be asked: the free run opens the device (once), and its limits are
    // the environment's. A study keeps its own device; the new one is opened when it is closed.
    auto environment = std::make_unique<session::TrialEnvironment>(uri.toStdString(), default_environment_->world(),
                                                                   default_environment_->rate_hz());
    if (study() != nullptr) {
      default_environment_ = std::move(environment);
      settings_->setValue("device/uri", uri);
      return true;
    }
    (void)rig_.finish();
    std::unique_ptr<session::TrialEnvironment> previous = std::move(default_environment_);
    default_environment_ = std::move(environment);
    if (const QString failed = useEnvironment(*default_environment_); !failed.isEmpty()) {
      default_environment_ = std::move(previous);  // the device that worked, running again
      (void)useEnvironment(*default_environment_);
      showError(tr("The device cannot be used"), failed);
      return false;
    }
    settings_->setValue("device/uri", uri);
    return true;
  } catch (const std::exception& e) {
    showError(tr("The device cannot be used"), what(e));
    return false;
  }
}

QString MainWindow::deviceUri() const { return qs(default_environment_->deviceUri()); }

bool MainWindow::loadTabletCalibration(const QString& file) {
  try {
    paper_->setTabletCalibration(hattr::studio::loadTabletCalibration(file.toStdString()));
    tablet_calibration_file_ = file;
    settings_->setValue("input/tablet_calibration", file);
    return true;
  } catch (const std::exception& e) {
    showError(tr("The tablet calibration could not be loaded"), what(e));
    return false;
  }
}

bool MainWindow::openReport() { return review_->openReport(); }

void MainWindow::setMode(guidance::TrainingMode mode) { train_tab_->setMode(mode); }

bool MainWindow::startTrial() { return train_tab_->start(); }

void MainWindow::beginLiveTrial(session::TrialEnvironment& environment, const session::TrialSetup& setup,
                                Activity kind, const HapticProfile& expert, bool reference_on_paper,
                                bool expert_on_plot, const QString& title, QLabel* scores) {
  // A reference the device cannot render (too strong, outside its workspace) is refused with
  // the numbers and the remedy, as `hattr train` refuses it (issue 38), against the limits of
  // the device the trial opens.
  session::TrialSetup checked = setup;
  checked.check_device = [&expert](const DeviceLimits& limits) { session::checkRenderable(expert, limits, "the reference"); };
  startRun(environment, trialRunSpec(checked, true), kind);
  trial_expert_ = &expert;
  // The paper: the reference (or not), nothing else; the plot: the trial's window.
  showReference(trial_expert_);
  paper_->setReferenceShown(reference_on_paper);
  paper_->overlay().clear();
  paper_->trail().clear();
  plot_->setExpert(expert_on_plot ? ForceSeries::fromProfile(expert, 4000, -expert.samples().front().t_s) : ForceSeries{});
  plot_->trainee().clear();
  plot_->setCursorTime(std::nullopt);
  plot_->setTimeWindow(std::make_pair(0.0, rig_.spec().duration_s));
  plot_->setTitle(title);
  scores->setText(tr("Trial running…"));
  refreshButtons();
}

bool MainWindow::stopTrial() {
  switch (activity_) {
    case Activity::kTrial:
    case Activity::kStudyTrial:
      // Still getting ready: nothing is recorded yet, so there is nothing to keep.
      if (rig_.status().settling) {
        abortActivity();
        statusBar()->showMessage(tr("Stopped before the trial began: nothing kept."), 5000);
        return true;
      }
      rig_.requestStop();
      finishTrial();
      return true;
    case Activity::kRecording: return stopRecording();
    case Activity::kMentoring: return mentor_->disconnectSession();  // the recording is kept
    case Activity::kFree:
    case Activity::kPlayback: return false;
  }
  return false;
}

void MainWindow::finishTrial() {
  session::TrialResult result = rig_.finish();
  const std::string failure = result.failure;
  const bool study_trial = activity_ == Activity::kStudyTrial;
  activity_ = Activity::kFree;
  startFreeRun();
  paper_->setReferenceCue(std::nullopt);
  // A study trial the device, the loop or an absent mentor broke off is not data (as the study
  // runner has it): the Study tab marks it failed.
  if (study_trial && !failure.empty()) {
    study_tab_->trialFailed(failure);
    refreshButtons();
    return;
  }
  if (!failure.empty() && result.profile.empty()) {
    train_tab_->scoresLabel()->setText(tr("The trial failed before it began; nothing kept."));
    showError(tr("The trial failed before it began"), qs(failure) + tr("\n\nNothing was recorded."));
    refreshButtons();
    return;
  }
  if (result.profile.empty()) {
    if (study_trial) study_tab_->trialAbandoned();  // it runs again
    showError(tr("The trial recorded nothing"), tr("the loop delivered no samples in the trial's window"));
    refreshButtons();
    return;
  }
  // Keep the trial before anything can fail.
  last_trial_ = result.profile;
  last_trial_expert_ = *trial_expert_;
  last_trial_saved_ = false;
  paper_->trail().assign(*last_trial_);
  plot_->setTrainee(ForceSeries::fromProfile(*last_trial_));
  plot_->setTimeWindow(std::nullopt);
  plot_holds_result_ = true;

  // A study trial goes to the study's database; its score is shown when the protocol says so.
  if (study_trial) {
    const StudyTab::Stored stored = study_tab_->trialEnded(std::move(result));
    last_trial_saved_ = stored.stored;
    if (stored.show_scores) {
      showScores(*last_trial_expert_, *last_trial_, study_tab_->scoresLabel());
    } else {
      last_scores_.reset();
    }
    refreshButtons();
    return;
  }
  // A training trial is scored, and is a point of the Train tab's learning curve unless it
  // was cut short.
  showScores(*last_trial_expert_, *last_trial_, train_tab_->scoresLabel());
  train_tab_->trialEnded(last_scores_, result);
  if (!failure.empty()) {
    showError(tr("The trial ended early"),
              qs(failure) + tr("\n\nWhat was recorded until then is kept and scored; it is no point of the learning curve."));
  }
  refreshButtons();
}

void MainWindow::showScores(const HapticProfile& expert, const HapticProfile& trial, QLabel* where) {
  try {
    const analysis::TrialScorer scorer(expert);
    const analysis::TrialScore scores = scorer.score(trial);
    last_scores_ = scores;
    if (!engineer_view_) {
      where->setText(tr("<b>Shape</b> %1 &nbsp; <b>Force</b> %2 &nbsp; <small>lower is closer to the model</small>")
                         .arg(scores.shape(), 0, 'f', 1)
                         .arg(scores.force(), 0, 'f', 1));
      return;
    }
    where->setText(tr("<b>Shape</b> (DTW x + y): %1 &nbsp; <b>Force</b> (DTW fx + fy + fz): %2<br>"
                      "<small>x %3 · y %4 · fx %5 · fy %6 · fz %7 · pen height z %9 (not in the shape) — the "
                      "paper's normalization, on the expert's %8 time steps; lower is closer</small>")
                       .arg(scores.shape(), 0, 'g', 4)
                       .arg(scores.force(), 0, 'g', 4)
                       .arg(scores.x, 0, 'g', 4)
                       .arg(scores.y, 0, 'g', 4)
                       .arg(scores.fx, 0, 'g', 4)
                       .arg(scores.fy, 0, 'g', 4)
                       .arg(scores.fz, 0, 'g', 4)
                       .arg(scorer.expertSamples())
                       .arg(scores.z, 0, 'g', 4));
  } catch (const std::exception& e) {
    last_scores_.reset();
    where->setText(tr("Not scored: %1").arg(what(e).toHtmlEscaped()));
  }
}

bool MainWindow::saveLastTrial(const QString& file) {
  if (!last_trial_) return false;
  return saveProfileTo(*last_trial_, file, last_trial_saved_);
}

// ---- Record (the Record tab's) --------------------------------------------------------------

const std::optional<HapticProfile>& MainWindow::take() const { return record_tab_->take(); }

bool MainWindow::startRecording() { return record_tab_->start(); }

bool MainWindow::stopRecording() { return record_tab_->stop(); }

bool MainWindow::saveTake(const QString& file) { return record_tab_->save(file); }

bool MainWindow::saveProfileTo(const HapticProfile& profile, const QString& file, bool& saved_flag) {
  try {
    SaveOutcome outcome = saveProfile(profile, file.toStdString(), false);
    if (outcome == SaveOutcome::kNeedsConfirmation) {
      if (!confirm(tr("%1 already exists. Replace it?").arg(file))) {
        last_error_ = tr("%1 already exists; not replaced").arg(file);
        return false;
      }
      outcome = saveProfile(profile, file.toStdString(), true);
    }
    saved_flag = outcome == SaveOutcome::kSaved;
    statusBar()->showMessage(tr("Saved %1").arg(file), 5000);
    return saved_flag;
  } catch (const std::exception& e) {
    showError(tr("Not saved (nothing is lost: it is still in memory)"), what(e));
    return false;
  }
}

// ---- Abort, playback, primary action ------------------------------------------------------------

void MainWindow::abortActivity() {
  switch (activity_) {
    case Activity::kTrial:
    case Activity::kStudyTrial:
    case Activity::kRecording:
      (void)rig_.finish();
      if (activity_ == Activity::kStudyTrial) study_tab_->trialAbandoned();  // it runs again
      if (activity_ == Activity::kRecording) record_tab_->aborted();
      if (activity_ == Activity::kTrial) train_tab_->aborted();
      activity_ = Activity::kFree;
      paper_->setReferenceCue(std::nullopt);
      startFreeRun();
      break;
    case Activity::kPlayback:
      playback_.pause(now_s());
      activity_ = Activity::kFree;
      plot_->setCursorTime(std::nullopt);
      break;
    case Activity::kMentoring: (void)mentor_->disconnectSession(); break;  // nothing recorded is lost
    case Activity::kFree: break;
  }
  refreshButtons();
}

void MainWindow::startPlayback(const HapticProfile* profile, const HapticProfile* expert) {
  if (profile == nullptr || profile->empty()) return;
  if (!idle()) return;
  playback_.load(profile);
  playback_.setSpeed(review_->speed());
  playback_expert_ = expert;
  showReference(expert);
  paper_->setReferenceShown(true);
  if (profile != review_->trial()) paper_->overlay().clear();  // a reviewed trial stays overlaid
  plot_holds_result_ = true;
  plot_->setExpert(expert != nullptr ? ForceSeries::fromProfile(*expert) : ForceSeries{});
  plot_->setTrainee(ForceSeries::fromProfile(*profile));
  plot_->setTimeWindow(std::nullopt);
  activity_ = Activity::kPlayback;
  playback_.play(now_s());
  refreshButtons();
}

void MainWindow::togglePlayback() {
  const double now = now_s();
  if (activity_ == Activity::kPlayback) {
    if (playback_.playing()) {
      playback_.pause(now);
    } else {
      playback_.play(now);
    }
    return;
  }
  // Nothing playing: play what the tab shows.
  switch (tabs_->currentIndex()) {
    case kTabRecord:
      if (take()) startPlayback(&*take(), nullptr);
      break;
    case kTabReview:
      if (review_->trial() != nullptr) startPlayback(review_->trial(), review_->expert());
      break;
    default:
      if (last_trial_) startPlayback(&*last_trial_, last_trial_expert_ ? &*last_trial_expert_ : nullptr);
      break;
  }
}

void MainWindow::clearTrail() {
  if (activity_ == Activity::kPlayback) abortActivity();
  paper_->trail().clear();
  paper_->overlay().clear();
  mentor_->clearPeerTrail();
}

void MainWindow::primaryAction() {
  switch (tabs_->currentIndex()) {
    case kTabRecord: record_tab_->toggle(); break;
    case kTabTrain:
      if (activity_ == Activity::kTrial) {
        stopTrial();
      } else {
        startTrial();
      }
      break;
    case kTabStudy: studyNext(); break;
    case kTabReview: togglePlayback(); break;
    case kTabMentor: mentor_->toggleSession(); break;
    default: break;
  }
}

// ---- Study (the Study tab's) ----------------------------------------------------------------

StudySession* MainWindow::study() const { return study_tab_->session(); }

bool MainWindow::openStudy(const QString& file) {
  if (!study_tab_->open(file)) return false;
  tabs_->setCurrentIndex(kTabStudy);
  return true;
}

bool MainWindow::selectStudySubject(const QString& subject) { return study_tab_->selectSubject(subject); }

bool MainWindow::studyNext() { return study_tab_->next(); }

void MainWindow::closeStudy() { study_tab_->closeStudy(); }

// ---- Review -------------------------------------------------------------------------------

bool MainWindow::openReview(const QString& file) {
  if (!review_->open(file)) return false;  // it refreshes the buttons (ReviewHost::changed)
  tabs_->setCurrentIndex(kTabReview);
  return true;
}

bool MainWindow::showReviewTrial(qint64 trial_id) { return review_->showTrial(trial_id); }

void MainWindow::showReviewed(const HapticProfile& trial, const HapticProfile& expert, const QString& title,
                              QLabel* scores) {
  if (activity_ == Activity::kPlayback) abortActivity();
  showReference(&expert);
  paper_->setReferenceShown(true);
  paper_->overlay().assign(trial);
  paper_->trail().clear();
  plot_->setExpert(ForceSeries::fromProfile(expert));
  plot_->setTrainee(ForceSeries::fromProfile(trial));
  plot_->setTimeWindow(std::nullopt);
  plot_->setCursorTime(std::nullopt);
  plot_holds_result_ = true;
  plot_->setTitle(title);
  showScores(expert, trial, scores);
  refreshButtons();
}

}  // namespace hattr::studio
