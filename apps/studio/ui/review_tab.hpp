#pragma once
/// The Review tab: a study database opened read-only, its subjects and trials in a tree with
/// each recall trial's shape and force costs (the study's stored analysis, or the one Open
/// report makes), a completed trial overlaid on the expert and played back, and the study's
/// report. The tab owns the database and what it shows of it; the paper, the plot and the
/// playback are the main window's, lent through ReviewHost. GUI thread only.

#include <QString>
#include <QWidget>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study_database.hpp"

class QComboBox;
class QLabel;
class QPushButton;
class QSettings;
class QTreeWidget;
class QTreeWidgetItem;
class QUrl;

namespace hattr::studio {

/// What the main window lends the tab.
struct ReviewHost {
  /// Whether a trial may be shown now (false while a trial, a recording or a session runs).
  std::function<bool()> may_show;
  /// Shows `trial` over `expert` on the paper and the plot (titled `title`), its scores in `scores`.
  std::function<void(const HapticProfile& trial, const HapticProfile& expert, const QString& title, QLabel* scores)>
      show;
  /// The study on show is going: stop a playback of `shown` (may be null), clear the overlay.
  std::function<void(const HapticProfile* shown)> forget;
  std::function<void()> toggle_playback;
  std::function<void(double speed)> set_speed;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<QString(const QString& title, const QString& filter)> ask_open_file;
  /// A passing message (the status bar).
  std::function<void(const QString& message)> note;
  /// Opens a URL (false when nothing could).
  std::function<bool(const QUrl& url)> open_url;
  /// What the tab has changed the window's buttons depend on (a study opened).
  std::function<void()> changed;
};

class ReviewTab final : public QWidget {
  Q_OBJECT

 public:
  /// The tree's columns (the costs before the status, so a narrow panel shows them).
  enum Column : int { kTrial = 0, kMode, kPhase, kShape, kForce, kStatus };

  ReviewTab(QSettings& settings, ReviewHost host, QWidget* parent = nullptr);
  ~ReviewTab() override;

  // ---- Actions (the buttons call these); false when refused. --------------------------------
  /// Opens a study database read-only; what the previous one showed goes.
  bool open(const QString& file);
  /// Shows the completed trial with this database id over the expert.
  bool showTrial(qint64 trial_id);
  /// Analyzes the study, writes its report next to the database (<stem>-report/), opens
  /// report.html, and shows the analysis's costs in the tree. The analysis and the files are made
  /// on a worker thread with its own read-only connection, while this thread's events go on (the
  /// window repaints, the live pen moves, a timer fires); the call returns when the report is
  /// written. Refused while a report is being written.
  bool openReport();
  /// A report is being written (openReport has not returned).
  [[nodiscard]] bool reporting() const { return reporting_; }

  /// The tree names strategies plainly ("Guided path") or technically ("PCONTROL").
  void setEngineerView(bool on);
  /// The trial on show and its expert (null when none).
  [[nodiscard]] const HapticProfile* trial() const { return trial_ ? &*trial_ : nullptr; }
  [[nodiscard]] const HapticProfile* expert() const { return expert_ ? &*expert_ : nullptr; }
  [[nodiscard]] bool studyOpen() const { return db_ != nullptr; }
  /// The playback speed chosen.
  [[nodiscard]] double speed() const;
  /// Enables the buttons: play when a trial is on show or `playback_loaded`.
  void refresh(bool playback_loaded);

  /// The widgets, so tests read what a person reads.
  struct Widgets {
    QLabel* study = nullptr;
    QTreeWidget* tree = nullptr;
    QLabel* costs = nullptr;   ///< where the tree's costs come from
    QLabel* scores = nullptr;  ///< the trial on show
    QPushButton* play = nullptr;
    QComboBox* speed = nullptr;
    QPushButton* report = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  void buildUi();
  void fillTree();
  /// The costs shown in the tree, by trial id, and where they come from.
  void useCosts(const std::vector<report::TrialCost>& costs, const QString& source);

  QSettings& settings_;
  ReviewHost host_;
  Widgets w_;
  std::unique_ptr<session::StudyDatabase> db_;
  QString file_;
  std::optional<HapticProfile> trial_;
  std::optional<HapticProfile> expert_;
  std::map<std::int64_t, report::TrialCost> costs_;
  bool engineer_view_ = false;
  bool reporting_ = false;
};

}  // namespace hattr::studio
