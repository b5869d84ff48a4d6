#pragma once
/// The Learners tab: a teacher's or therapist's learners and their practice plans, without
/// JSON or a terminal. A practice folder (remembered) holds one folder per learner and a study
/// database per plan (ops/practice_plan.hpp). New learner and New plan are two short forms;
/// Continue opens the plan's next session in the Study tab, which stores every trial as it
/// ends; the progress of the plan picked shows below (report/learner_progress.hpp: a sentence
/// a session, the curve, best and latest) and prints to a self-contained HTML page.
/// GUI thread only.

#include <QString>
#include <QWidget>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "hattr/ops/practice_plan.hpp"
#include "hattr/report/learner_progress.hpp"

class QLabel;
class QPushButton;
class QSettings;
class QTextBrowser;
class QTreeWidget;
class QUrl;

namespace hattr::studio {

class ProgressCurve;

/// What the main window lends the tab.
struct LearnersHost {
  /// Opens `file` in the Study tab with `learner` picked and begins their next session (asking
  /// first when it is early); false when refused (the window said why).
  std::function<bool(const QString& file, const QString& learner)> continue_plan;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<QString(const QString& title, const QString& suggested)> ask_save_file;
  std::function<QString(const QString& title, const QString& start)> ask_folder;
  std::function<bool(const QUrl& url)> open_url;
  std::function<void(const QString& message, int ms)> note;
};

class LearnersTab final : public QWidget {
  Q_OBJECT

 public:
  LearnersTab(QSettings& settings, LearnersHost host, QWidget* parent = nullptr);
  ~LearnersTab() override;

  // ---- Actions (the buttons call these); false when refused. ---------------------------------
  /// The practice folder (created when missing; remembered).
  bool setFolder(const QString& folder);
  [[nodiscard]] const QString& folder() const { return folder_; }
  /// Lists the folder's plans again (keeps the plan picked).
  void refresh();
  /// The New learner form, then the New plan form for them: the learner is stored with the plan.
  bool newLearner();
  /// The New plan form for the learner of the plan picked.
  bool newPlan();
  /// Makes a plan in the folder (a new learner's first, or another), lists it and picks it.
  bool createPlan(const ops::PracticePlanOptions& options);
  /// Picks a plan by its file; its progress shows.
  bool selectPlan(const QString& file);
  /// The plan picked: its next session in the Study tab.
  bool continuePlan();
  /// Reads the picked plan's progress again and shows it.
  bool showProgress();
  /// Writes the printable page of the progress on show (asks where when `file` is empty) and
  /// opens it for printing.
  bool printProgress(const QString& file = {});

  [[nodiscard]] const std::vector<ops::PracticePlanSummary>& plans() const { return plans_; }
  [[nodiscard]] const ops::PracticePlanSummary* selectedPlan() const;
  [[nodiscard]] const std::optional<report::LearnerProgress>& progress() const { return progress_; }

  struct Widgets {
    QLabel* folder = nullptr;
    QPushButton* change_folder = nullptr;
    QTreeWidget* list = nullptr;
    QPushButton* new_learner = nullptr;
    QPushButton* new_plan = nullptr;
    QPushButton* continue_plan = nullptr;
    QPushButton* print = nullptr;
    QLabel* summary = nullptr;
    QTextBrowser* sessions = nullptr;
    ProgressCurve* curve = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 protected:
  void showEvent(QShowEvent* event) override;

 private:
  void buildUi();
  void fillList();
  /// The list's row of the plan picked becomes the current one (no signal).
  void markPicked();
  void refreshButtons();
  /// The learner of the plan picked (with the details of their latest plan).
  [[nodiscard]] std::optional<session::Learner> selectedLearner() const;
  /// The New plan form for `learner`, kept open until the plan can be made; then makes it.
  bool askPlan(const session::Learner& learner);

  QSettings& settings_;
  LearnersHost host_;
  Widgets w_;
  QString folder_;
  std::vector<ops::PracticePlanSummary> plans_;
  QString selected_;  ///< the plan picked (its file)
  std::optional<report::LearnerProgress> progress_;
  std::map<std::string, report::ScoreCache> scores_;  ///< by plan file: its trials' scores so far
};

/// The practice folder when none was chosen: "hattr practice" in the user's documents.
[[nodiscard]] QString defaultPracticeFolder();

}  // namespace hattr::studio
