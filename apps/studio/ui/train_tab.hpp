#pragma once
/// The Train tab: the training reference (a profile file, a person's template in a profile
/// library, a letter the simulated expert writes or the Record tab's take), the
/// strategy (every one but the mentored, by its plain name; a scheduled one's law and gain set
/// from this reference's trials in it so far) with its indexing and get-ready time, a trial
/// against the reference, its scores and the learning curve. The tab owns the reference, the mode and its widgets, and
/// sets a trial up for session::runTrial's pipeline; the rig, the paper, the plot and the last
/// trial are the main window's, lent through TrainHost. GUI thread only.

#include <QString>
#include <QWidget>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/session/trial.hpp"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QPushButton;
class QSettings;
class QVBoxLayout;

namespace hattr::studio {

class LearningCurve;

/// What the main window lends the tab.
struct TrainHost {
  /// Nothing runs on the rig but the free writing (a playback may play: it is stopped first).
  std::function<bool()> idle;
  /// A training trial of this tab runs on the rig.
  std::function<bool()> trial_running;
  /// The reference may change now (no training or study trial runs).
  std::function<bool()> may_change_reference;
  /// The servo rate of the paper the trial runs on [Hz].
  std::function<double()> rate_hz;
  /// Starts a live training trial of `setup` against `expert` (drawn on the paper when
  /// `reference_on_paper`), titled `title`, its scores in `scores`. Throws what the rig throws.
  std::function<void(const session::TrialSetup& setup, const HapticProfile& expert, bool reference_on_paper,
                     const QString& title, QLabel* scores)>
      start_trial;
  /// Ends the running trial now and keeps it (the stop key).
  std::function<void()> stop_trial;
  /// Switches the running trial's mode through the servo mailbox (false: the mailbox is full).
  std::function<bool(guidance::TrainingMode mode)> switch_mode;
  /// A new reference: shown alone on the paper (drawn when `shown`) and the plot, unless a
  /// trial or a session has them.
  std::function<void(const HapticProfile& reference, bool shown)> show_reference;
  /// "Show the reference" was toggled.
  std::function<void(bool shown)> reference_shown;
  /// The last trial (training or study): whether there is one, it (null: none), replay it, save
  /// it (asks where).
  std::function<bool()> has_last_trial;
  std::function<const HapticProfile*()> last_trial;
  std::function<void()> replay_last_trial;
  std::function<void()> save_last_trial;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<QString(const QString& title, const QString& filter)> ask_open_file;
  /// What the tab has changed the window's buttons depend on.
  std::function<void()> changed;
};

/// How the Record tab's take is named when it is the reference.
struct TakeName {
  QString file;       ///< where it was saved (empty: not saved)
  QString expert;     ///< as typed ("unnamed" when empty)
  QString character;  ///< as typed ("no character" when empty)
};

class TrainTab final : public QWidget {
  Q_OBJECT

 public:
  TrainTab(QSettings& settings, TrainHost host, QWidget* parent = nullptr);
  ~TrainTab() override;

  // ---- Actions (the buttons and keys call these); false when refused. ------------------------
  /// Loads a reference profile, or a template library:PATH#PERSON/SKILL (refused while a trial runs).
  bool loadReference(const QString& file);
  /// Opens the profile library at `location` in its dialog (LibraryDialog): a person's template
  /// chosen there becomes the reference; their nearest persons can be found for the last trial
  /// or a file. False when it is not a library, or nothing was chosen.
  bool openLibrary(const QString& location);
  /// The take becomes the reference, named by `name` (refused while anything runs).
  bool useTake(const HapticProfile& take, const TakeName& name);
  /// A built-in glyph (a letter of the library, ந, the loop; by name or character) written by
  /// the simulated expert on the simulated pen becomes the reference (refused while a trial runs).
  bool useLetter(const QString& glyph);
  /// The take that is the reference was saved: it is named by its file from now on.
  void takeRenamed(const TakeName& name);
  /// The take went (a new recording): a reference made of it stays, as a take nobody can save.
  void takeGone() { reference_is_take_ = false; }
  /// The training mode; during a trial it switches through the servo mailbox (cross-fade).
  void setMode(guidance::TrainingMode mode);
  /// Starts a trial against the reference in the mode, in real time.
  bool start();
  /// A training trial ended, scored (`scores`, none when it could not be) unless it recorded
  /// nothing; `failure` non-empty: the device or the loop cut it short, and it is no point of
  /// the learning curve. `result`'s counters are added to the scores.
  void trialEnded(const std::optional<analysis::TrialScore>& scores, const session::TrialResult& result);
  /// The trial was aborted: nothing kept.
  void aborted();
  /// Strategies by their plain names only, or with the technical name beside; the loop's
  /// counters after a trial only in the engineer view.
  void setEngineerView(bool on);

  /// Enables the buttons for what the window does now.
  void refresh();
  /// The mode, indexing, get-ready time, "show the reference" and the reference file, remembered.
  void saveSettings();

  [[nodiscard]] guidance::TrainingMode mode() const { return mode_; }
  /// The reference (null: none).
  [[nodiscard]] const HapticProfile* reference() const { return reference_ ? &*reference_ : nullptr; }
  /// Whether the reference is drawn during training.
  [[nodiscard]] bool referenceShown() const;
  /// The person's "get ready" before each trial [s] (not recorded); the Study tab's too.
  [[nodiscard]] double settle_s() const;
  [[nodiscard]] QLabel* scoresLabel() const { return w_.scores; }
  [[nodiscard]] LearningCurve* learningCurve() const { return w_.curve; }

  /// The widgets, so tests read what a person reads.
  struct Widgets {
    QLabel* reference = nullptr;
    QPushButton* library = nullptr;  ///< "From a profile library…"
    QComboBox* letter = nullptr;  ///< "Or a letter": the built-in glyphs by character
    QComboBox* mode = nullptr;
    QComboBox* indexing = nullptr;
    QCheckBox* show_reference = nullptr;
    QDoubleSpinBox* settle = nullptr;
    QPushButton* trial = nullptr;
    QPushButton* replay = nullptr;
    QPushButton* save = nullptr;
    QLabel* scores = nullptr;
    LearningCurve* curve = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  void buildUi();
  void buildReferenceChoice(QVBoxLayout& layout);
  /// Whether the reference may change now (no trial runs); if not, the window says why.
  bool referenceMayChange();
  /// The training reference, read from `file` (empty: not from a file, not remembered), named
  /// `name` in trials' metadata, described by `label_html`.
  void setReference(HapticProfile profile, const QString& file, const QString& name, const QString& label_html);
  void nameTake(const TakeName& name);

  QSettings& settings_;
  TrainHost host_;
  Widgets w_;
  std::optional<HapticProfile> reference_;
  QString reference_file_;  // remembered in settings; empty for an unsaved take
  QString reference_letter_;  // the built-in glyph written as the reference (remembered), or empty
  QString reference_name_;  // in the trials' metadata (reference_file)
  bool reference_is_take_ = false;  // the reference is the Record tab's take
  bool engineer_view_ = false;
  guidance::TrainingMode mode_ = guidance::TrainingMode::kBasic;
  guidance::TrainingMode trial_mode_ = guidance::TrainingMode::kBasic;  // the mode the trial started in
  // A scheduled strategy's tracking errors of this reference's trials in it, in order.
  std::map<guidance::TrainingMode, std::vector<double>> scheduled_errors_;
};

}  // namespace hattr::studio
