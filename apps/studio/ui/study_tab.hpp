#pragma once
/// The Study tab: a person's study session from a study database (core/study_session.hpp).
/// The tab owns the session and what it shows of it: the study, the subject picker, the
/// progress, the prompt and the trial's outcome. The live rig, the paper and the plot are the
/// main window's, lent through StudyHost: the tab asks the window to start a trial, and the
/// window hands the trial's end back (trialFailed, trialAbandoned, trialEnded).
/// GUI thread only.

#include <QString>
#include <QWidget>
#include <functional>
#include <memory>
#include <string>

#include "core/study_session.hpp"
#include "hattr/session/trial.hpp"

class QComboBox;
class QLabel;
class QPushButton;
class QSettings;

namespace hattr::studio {

/// What the main window lends the tab.
struct StudyHost {
  /// Nothing runs on the rig but the free writing (a playback may play: it is stopped first).
  std::function<bool()> idle;
  /// A trial of this study runs on the rig.
  std::function<bool()> trial_running;
  /// The rig or the device is in use (a trial, a recording or a mentoring session): the study,
  /// whose paper they run on, cannot close.
  std::function<bool()> device_busy;
  /// What the previous tab left on show goes: a playback stops; the overlay, the trail and the
  /// plot are cleared.
  std::function<void()> clear_views;
  /// The rig runs free writing on this environment from now (null: the window's own, with the
  /// Train tab's reference back on the paper).
  std::function<void(session::TrialEnvironment* environment)> use_environment;
  /// `expert` becomes the reference on the paper (null: none), drawn when `shown`.
  std::function<void(const HapticProfile* expert, bool shown)> show_reference;
  /// The reference goes from sight, on the paper and the plot (a recall trial is announced).
  std::function<void()> hide_reference;
  /// Starts a live trial of `setup` on `environment` against `expert` (its reference shown on
  /// the paper and plot when `shows_reference`), titled `title`, scored in `scores`. Throws
  /// what the rig throws.
  std::function<void(session::TrialEnvironment& environment, const session::TrialSetup& setup,
                     const HapticProfile& expert, bool shows_reference, const QString& title, QLabel* scores)>
      start_trial;
  /// Ends the running trial now and keeps it (the stop key).
  std::function<void()> stop_trial;
  /// The person's "get ready" before each trial [s] (not recorded).
  std::function<double()> settle_s;
  /// The window's clock [s] (rests are timed on it).
  std::function<double()> now_s;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<bool(const QString& question)> confirm;
  std::function<QString(const QString& title, const QString& filter)> ask_open_file;
  /// A passing message (the status bar) for `ms` milliseconds.
  std::function<void(const QString& message, int ms)> note;
  /// What the tab has changed the window's buttons depend on.
  std::function<void()> changed;
};

class StudyTab final : public QWidget {
  Q_OBJECT

 public:
  StudyTab(QSettings& settings, StudyHost host, QWidget* parent = nullptr);
  ~StudyTab() override;

  // ---- Actions (the buttons and keys call these); false when refused. ------------------------
  /// Opens a study database; the study open before is closed.
  bool open(const QString& file);
  /// Picks the subject whose trials run next (a non-person participant only when confirmed).
  bool selectSubject(const QString& subject);
  /// Cuts the rest short and starts the next trial; between sessions, begins the next session
  /// (asking first when it is early).
  bool next();
  /// Closes the study; the rig goes back to the window's own paper and device.
  void closeStudy();

  // ---- A trial's end, handed back by the window. ----------------------------------------------
  /// The device, the loop or an absent mentor broke the trial off: as the study runner does, it
  /// is marked failed in the database (nothing of it stored), and the study runs it again.
  void trialFailed(const std::string& failure);
  /// The trial recorded nothing, or was aborted: the study runs it again.
  void trialAbandoned();
  /// What became of a trial that recorded something.
  struct Stored {
    bool stored = false;       ///< it is in the study database
    bool show_scores = false;  ///< the protocol shows the subject a score (protocol.show_scores)
  };
  /// Stores the trial in the study database (a database that refuses it leaves it to the
  /// window's "Save last trial"; the study runs the trial again).
  Stored trialEnded(session::TrialResult result);

  /// While nothing runs: advances the rests and says what the subject sees over the paper
  /// (rest countdown, prompt, thanks), empty when nothing.
  QString idleBanner();
  /// Enables the buttons for what the window does now.
  void refresh();
  /// The prompts name strategies technically ("Training with ALPHA") or plainly ("Training with
  /// Guided pressure").
  void setEngineerView(bool on);

  [[nodiscard]] StudySession* session() const { return study_.get(); }
  /// Where a study trial's scores are shown.
  [[nodiscard]] QLabel* scoresLabel() const { return w_.scores; }

  /// The widgets, so tests read what a person reads.
  struct Widgets {
    QLabel* study = nullptr;
    QComboBox* subject = nullptr;
    QPushButton* begin = nullptr;
    QLabel* progress = nullptr;
    QLabel* prompt = nullptr;
    QPushButton* next = nullptr;
    QPushButton* close = nullptr;
    QLabel* scores = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  /// Begins the subject's next session (asking first when it is early).
  bool beginNextSession();
  void buildUi();
  void fillSubjects();
  /// The progress and the prompt; a recall trial's reference hidden from its announcement on.
  void refreshPanel();
  /// The runner's prompt as this view words it.
  [[nodiscard]] QString promptText() const;

  QSettings& settings_;
  StudyHost host_;
  Widgets w_;
  std::unique_ptr<StudySession> study_;
  bool engineer_view_ = false;
};

}  // namespace hattr::studio
