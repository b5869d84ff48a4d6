#pragma once
/// The Record tab: an expert's take, recorded on the live rig with the pen-down trigger or the
/// Record/Stop buttons, reviewed, saved as a haptic profile, or made the Train tab's reference.
/// The tab owns the take and its widgets, and watches the rig while it records; the rig run,
/// the paper and the plot are the main window's, lent through RecordHost. GUI thread only.

#include <QString>
#include <QWidget>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/live_rig.hpp"
#include "hattr/core/haptic_profile.hpp"

class QComboBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QSettings;

namespace hattr::studio {

/// What the main window lends the tab.
struct RecordHost {
  /// Nothing runs on the rig but the free writing (a playback may play: it is stopped first).
  std::function<bool()> idle;
  /// A recording of this tab runs on the rig.
  std::function<bool()> recording;
  /// Starts the rig recording `spec` on the window's paper; the trail, the overlay and the
  /// plot's trace are cleared. Throws what the rig throws (free writing goes on).
  std::function<void(const RunSpec& spec)> begin;
  /// Ends the rig's recording run, returns what it recorded; free writing goes on.
  std::function<session::TrialResult()> end;
  /// A take on show: its trail on the paper and its forces alone on the plot.
  std::function<void(const HapticProfile& take)> show;
  /// Plays `take` back.
  std::function<void(const HapticProfile& take)> play;
  /// A letter guide to trace while recording (its strokes in the paper plane [m]; empty: none).
  std::function<void(const std::vector<std::vector<Eigen::Vector2d>>& strokes_m)> show_guide;
  /// Makes `take` the Train tab's reference (false: refused, the window said why).
  std::function<bool(const HapticProfile& take)> use_as_reference;
  /// The take was saved to a file, or went: a reference made of it is renamed, or stays as an
  /// unsaved take.
  std::function<void()> take_changed;
  /// Saves `profile` to `file` (asks before replacing one); `saved` says whether it was.
  std::function<bool(const HapticProfile& profile, const QString& file, bool& saved)> save;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<bool(const QString& question)> confirm;
  std::function<QString(const QString& title, const QString& suggested)> ask_save_file;
  /// What the tab has changed the window's buttons depend on.
  std::function<void()> changed;
};

class RecordTab final : public QWidget {
  Q_OBJECT

 public:
  RecordTab(LiveRig& rig, QSettings& settings, RecordHost host, QWidget* parent = nullptr);
  ~RecordTab() override;

  // ---- Actions (the buttons and keys call these); false when refused. ------------------------
  /// Starts recording a take (an unsaved take goes only when confirmed).
  bool start();
  /// Stops the recording and keeps the take (its end_reason "stopped", unless the pen-up
  /// trigger ended it first).
  bool stop();
  /// Record / Stop recording (the R key).
  void toggle();
  /// Saves the take, named as typed, as a haptic profile.
  bool save(const QString& file);
  /// Asks where, then saves the take (Ctrl+S).
  void askSave();
  /// Makes the take the training reference, unsaved or not.
  bool useAsReference();
  /// The window aborted the recording: nothing is kept.
  void aborted();
  /// A letter of the library (a built-in glyph's name, "small-a"; "" none) drawn on the paper to
  /// trace, numbered and arrowed stroke by stroke; the character field takes its name when it
  /// was empty or the last guide's. Remembered.
  bool setLetterGuide(const QString& glyph_name);
  [[nodiscard]] const std::vector<std::vector<Eigen::Vector2d>>& guideStrokes() const { return guide_m_; }

  /// While recording: arms the Record/Stop trigger once the pen has settled, stops a pen-down
  /// take once the pen is up, and says what the expert sees over the paper.
  QString recordingBanner();
  /// Enables the buttons for what the window does now.
  void refresh();
  /// Whether the window may close: an unsaved take goes only when confirmed.
  bool mayClose();
  /// The expert's name, the character and the trigger, remembered.
  void saveSettings();

  [[nodiscard]] const std::optional<HapticProfile>& take() const { return take_; }
  /// Where the take was saved (empty: not saved).
  [[nodiscard]] const QString& takeFile() const { return take_file_; }
  /// The expert and the character as typed ("unnamed", "no character" when empty).
  [[nodiscard]] QString expertName() const;
  [[nodiscard]] QString character() const;

  /// The widgets, so tests read what a person reads.
  struct Widgets {
    QLineEdit* expert = nullptr;
    QLineEdit* character = nullptr;
    QComboBox* trigger = nullptr;
    QComboBox* guide = nullptr;
    QPushButton* record = nullptr;
    QPushButton* replay = nullptr;
    QPushButton* retake = nullptr;
    QPushButton* save = nullptr;
    QPushButton* use = nullptr;
    QLabel* take = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  void buildUi();
  void forgetTake();

  LiveRig& rig_;
  QSettings& settings_;
  RecordHost host_;
  Widgets w_;
  std::optional<HapticProfile> take_;
  bool take_saved_ = true;
  QString take_file_;             // where the take was saved (empty: not saved)
  bool armed_ = false;            // Record/Stop trigger: armed once the settle phase is over
  QString guide_name_;            // the letter guide's glyph ("" none)
  std::vector<std::vector<Eigen::Vector2d>> guide_m_;
};

}  // namespace hattr::studio
