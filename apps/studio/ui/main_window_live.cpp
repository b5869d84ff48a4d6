// The main window's live side: the rig on the paper, the display at frame rate, the status
// bar, the buttons; and its dialogs.
#include "ui/main_window.hpp"

#include "hattr/guidance/strategy_catalog.hpp"

#include <QApplication>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QStatusBar>
#include <cmath>

#include "core/device_choice.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
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

constexpr double kRollingWindow_s = 5.0;  // the plot's window while writing freely

}  // namespace

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
         "over udp://); a hardware pen (plugin:, udp://, the open pen on serial://) is held by the person.\n\n%1")
          .arg(qs(device::deviceUriHelp())),
      QLineEdit::Normal, deviceUri(), &ok);
  if (ok && !uri.trimmed().isEmpty()) (void)setDevice(uri.trimmed());
}


// ---- The live rig and the display -----------------------------------------------------------

void MainWindow::refreshWorldLabel() {
  if (environment_ == nullptr) return;
  QString clamps;
  const std::vector<std::string> none;
  for (const auto& line : environment_->limitsBound() ? environment_->worldClamps() : none) {
    clamps += QStringLiteral("<br>· ") + qs(line).toHtmlEscaped();
  }
  if (!engineer_view_) clamps.clear();  // the passivity bounds' detail is the engineer's
  world_label_->setText(tr("Device <tt>%1</tt> at %2 Hz; world: %3%4")
                            .arg(qs(environment_->deviceUri()).toHtmlEscaped())
                            .arg(environment_->rate_hz())
                            .arg(world_file_.isEmpty() ? tr("defaults") : world_file_.toHtmlEscaped())
                            .arg(clamps.isEmpty() ? QString() : tr("<br>Clamped to the device:%1").arg(clamps)));
}

QString MainWindow::useEnvironment(session::TrialEnvironment& environment) {
  environment_ = &environment;
  // The free run opens the device (once): a device other than a simulated pen says its limits then.
  const QString failed = tryFreeRun();
  if (environment.limitsBound()) {
    const DeviceLimits& limits = environment.limits();
    paper_->setPaper(environment.paper().relief(), limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                     limits.workspace_max_m.x(), limits.workspace_max_m.y());
    scene_->setPaper(environment.paper().relief(), limits.workspace_min_m.x(), limits.workspace_min_m.y(),
                     limits.workspace_max_m.x(), limits.workspace_max_m.y());
    paper_->setForceLimit(limits.continuous_force_N);
  }
  refreshWorldLabel();
  return failed;
}

void MainWindow::startFreeRunOn(session::TrialEnvironment& environment) {
  if (const QString failed = useEnvironment(environment); !failed.isEmpty()) {
    showError(tr("The servo loop could not start"), failed);
  }
}

QString MainWindow::tryFreeRun() {
  RunSpec spec;
  spec.metadata.subject = "studio";
  QString failed;
  try {
    rig_.start(*environment_, spec, hand_, session::Clock::kRealTime);
  } catch (const std::exception& e) {
    failed = QString::fromUtf8(e.what());
  }
  if (activity_ != Activity::kPlayback) activity_ = Activity::kFree;
  return failed;
}

void MainWindow::startFreeRun() {
  if (const QString failed = tryFreeRun(); !failed.isEmpty()) showError(tr("The servo loop could not start"), failed);
}

void MainWindow::startRun(session::TrialEnvironment& environment, const RunSpec& spec, Activity kind) {
  if (activity_ == Activity::kPlayback) abortActivity();
  playback_.load(nullptr);
  try {
    rig_.start(environment, spec, hand_, session::Clock::kRealTime);
  } catch (...) {
    startFreeRun();
    throw;
  }
  activity_ = kind;
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
  // The loop: measured rate, overruns, faults, drops, stalls (the engineer view); plainly, only
  // whether it keeps time.
  const bool mentoring = activity_ == Activity::kMentoring;
  const servo::LiveCounters* counters = mentoring ? mentor_->counters() : rig_.counters();
  if (counters == nullptr) {
    status_loop_->setText(engineer_view_ ? tr("Loop: stopped") : tr("Pen: stopped"));
  } else {
    const std::uint64_t ticks = counters->ticks.load();
    if (ticks >= last_ticks_ && now > last_status_s_) {
      loop_rate_hz_ = static_cast<double>(ticks - last_ticks_) / (now - last_status_s_);
    }
    last_ticks_ = ticks;
    const double rate_hz = environment_ != nullptr ? environment_->rate_hz() : 1000.0;
    const bool keeps_time = counters->faults.load() == 0 && loop_rate_hz_ >= 0.9 * rate_hz;
    status_loop_->setText(engineer_view_ ? tr("Loop: %1 Hz · overruns %2 · faults %3 · drops %4 · stalls %5 · %6")
                                               .arg(loop_rate_hz_, 0, 'f', 0)
                                               .arg(counters->overruns.load())
                                               .arg(counters->faults.load())
                                               .arg(counters->dropped_samples.load())
                                               .arg(counters->stalls.load() + counters->consumer_stalls.load())
                                               .arg(mentoring ? tr("mentoring station") : qs(rig_.realtimeSummary()))
                         : loop_rate_hz_ <= 0.0 ? tr("Pen: starting")
                         : keeps_time          ? tr("Pen: ready")
                                               : tr("Pen: not keeping time (View ▸ Engineer view says why)"));
  }
  last_status_s_ = now;
  static const char* kNames[] = {"writing", "recording", "training trial", "study trial", "playback", "mentoring"};
  // The mode the loop runs: a study trial's own (a recall trial is BASIC whatever its mode),
  // otherwise the Train tab's.
  const guidance::TrainingMode shown = activity_ == Activity::kStudyTrial ? rig_.spec().guidance.mode : train_tab_->mode();
  const QString strategy = engineer_view_ ? qs(std::string(guidance::modeName(shown)))
                                          : qs(guidance::strategyInfo(shown).plain_name);
  status_activity_->setText(tr("Activity: %1 · %2 %3")
                                .arg(QString::fromLatin1(kNames[static_cast<int>(activity_)]))
                                .arg(engineer_view_ ? tr("mode") : tr("help:"), strategy));
}

void MainWindow::setEngineerView(bool on) {
  engineer_view_ = on;
  if (engineer_action_ != nullptr) {
    const QSignalBlocker block(engineer_action_);
    engineer_action_->setChecked(on);
  }
  paper_->setEngineerView(on);
  train_tab_->setEngineerView(on);
  study_tab_->setEngineerView(on);
  mentor_->setEngineerView(on);
  review_->setEngineerView(on);
  refreshWorldLabel();
  onStatus();
  paper_->update();
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
