#include "ui/learners_tab.hpp"

#include <QDir>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QSplitter>
#include <QStandardPaths>
#include <QTextBrowser>
#include <QTreeWidget>
#include <QTreeWidgetItemIterator>
#include <QUrl>
#include <QVBoxLayout>

#include "hattr/core/atomic_file.hpp"
#include "hattr/core/error.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/session/study_database.hpp"
#include "ui/learner_dialogs.hpp"
#include "ui/progress_curve.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

constexpr int kFileRole = Qt::UserRole;

QString learnerTitle(const session::Learner& l) {
  QString text = qs(session::displayName(l));
  if (l.age_years) text += QObject::tr(", %1 years").arg(*l.age_years);
  return text;
}

QString planLine(const ops::PracticePlanSummary& p) {
  QString letters;
  for (const auto& l : p.letters) letters += (letters.isEmpty() ? "" : " ") + qs(l);
  return QObject::tr("%1: %2 · %3").arg(qs(p.file.stem().string()), letters, qs(guidance::strategyInfo(p.strategy).plain_name));
}

}  // namespace

QString defaultPracticeFolder() {
  return QDir(QStandardPaths::writableLocation(QStandardPaths::DocumentsLocation)).filePath(QStringLiteral("hattr practice"));
}

LearnersTab::LearnersTab(QSettings& settings, LearnersHost host, QWidget* parent)
    : QWidget(parent), settings_(settings), host_(std::move(host)) {
  buildUi();
  folder_ = settings_.value(QStringLiteral("learners/folder"), defaultPracticeFolder()).toString();
  w_.folder->setText(tr("Practice folder: %1").arg(folder_));
  refreshButtons();
}

LearnersTab::~LearnersTab() = default;

void LearnersTab::buildUi() {
  w_.folder = wrappedLabel();
  w_.change_folder = new QPushButton(tr("Change…"));
  w_.list = new QTreeWidget;
  w_.list->setObjectName("learners_list");
  w_.list->setHeaderLabels({tr("Learner and plan"), tr("Done"), tr("Next")});
  w_.list->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  w_.new_learner = new QPushButton(tr("New learner…"));
  w_.new_learner->setObjectName("learners_new");
  w_.new_plan = new QPushButton(tr("New plan…"));
  w_.new_plan->setObjectName("learners_new_plan");
  w_.continue_plan = new QPushButton(tr("Continue"));
  w_.continue_plan->setObjectName("learners_continue");
  w_.continue_plan->setToolTip(tr("The plan's next session, in the Study tab"));
  w_.print = new QPushButton(tr("Print progress…"));
  w_.print->setObjectName("learners_print");
  w_.print->setToolTip(tr("A page for parents or a clinic: saved as a web page and opened to print"));
  w_.summary = wrappedLabel();
  w_.summary->setObjectName("learners_summary");
  w_.sessions = new QTextBrowser;
  w_.sessions->setObjectName("learners_progress");
  w_.curve = new ProgressCurve;

  auto* folder_row = new QHBoxLayout;
  folder_row->addWidget(w_.folder, 1);
  folder_row->addWidget(w_.change_folder);
  auto* buttons = new QHBoxLayout;
  for (QPushButton* b : {w_.new_learner, w_.new_plan, w_.continue_plan, w_.print}) buttons->addWidget(b);
  auto* split = new QSplitter(Qt::Vertical);
  split->addWidget(w_.list);
  split->addWidget(w_.curve);
  split->addWidget(w_.sessions);
  split->setStretchFactor(0, 1);  // the list is short; the progress gets the room
  split->setStretchFactor(1, 2);
  split->setStretchFactor(2, 3);
  auto* layout = new QVBoxLayout(this);
  layout->addLayout(folder_row);
  layout->addLayout(buttons);
  layout->addWidget(w_.summary);
  layout->addWidget(split, 1);

  connect(w_.change_folder, &QPushButton::clicked, this, [this] {
    const QString chosen = host_.ask_folder(tr("Practice folder"), folder_);
    if (!chosen.isEmpty()) (void)setFolder(chosen);
  });
  connect(w_.new_learner, &QPushButton::clicked, this, [this] { (void)newLearner(); });
  connect(w_.new_plan, &QPushButton::clicked, this, [this] { (void)newPlan(); });
  connect(w_.continue_plan, &QPushButton::clicked, this, [this] { (void)continuePlan(); });
  connect(w_.print, &QPushButton::clicked, this, [this] { (void)printProgress(); });
  connect(w_.list, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    const QString file = item != nullptr ? item->data(0, kFileRole).toString() : QString();
    if (!file.isEmpty() && file != selected_) (void)selectPlan(file);
  });
}

void LearnersTab::showEvent(QShowEvent* event) {
  QWidget::showEvent(event);
  refresh();  // trials written in the Study tab since
}

bool LearnersTab::setFolder(const QString& folder) {
  if (!QDir().mkpath(folder)) {
    host_.error(tr("Cannot use this practice folder"), tr("%1: cannot be created or written").arg(folder));
    return false;
  }
  folder_ = folder;
  settings_.setValue(QStringLiteral("learners/folder"), folder_);
  w_.folder->setText(tr("Practice folder: %1").arg(folder_));
  selected_.clear();
  refresh();
  return true;
}

void LearnersTab::refresh() {
  std::vector<std::string> skipped;
  try {
    QDir().mkpath(folder_);  // the first time, the folder chosen (or the default) is made
    plans_ = ops::listPracticePlans(folder_.toStdString(), session::localToday(), &skipped);
  } catch (const std::exception& e) {
    plans_.clear();
    w_.summary->setText(tr("The practice folder cannot be read: %1").arg(what(e).toHtmlEscaped()));
  }
  if (!skipped.empty()) host_.note(tr("Left out: %1").arg(qs(skipped.front())), 8000);
  fillList();
  if (!selected_.isEmpty()) (void)showProgress();
  refreshButtons();
}

// One row a learner (with their latest plan's details), their plans under it.
void LearnersTab::fillList() {
  const QSignalBlocker block(w_.list);
  w_.list->clear();
  QTreeWidgetItem* learner = nullptr;
  for (const auto& p : plans_) {
    if (learner == nullptr || learner->data(1, kFileRole).toString() != qs(p.learner.code)) {
      learner = new QTreeWidgetItem(w_.list);
      learner->setData(1, kFileRole, qs(p.learner.code));
      learner->setExpanded(true);
    }
    learner->setText(0, learnerTitle(p.learner));
    learner->setData(0, kFileRole, qs(p.file.string()));  // the learner's row picks their latest plan
    auto* plan = new QTreeWidgetItem(learner, {planLine(p), tr("%1 of %2").arg(p.trials_completed).arg(p.trials_total),
                                               qs(session::scheduleText(p.schedule))});
    plan->setData(0, kFileRole, qs(p.file.string()));
  }
  w_.list->expandAll();
  markPicked();
}

void LearnersTab::markPicked() {
  const QSignalBlocker block(w_.list);
  for (QTreeWidgetItemIterator it(w_.list); *it != nullptr; ++it) {
    const bool plan_row = (*it)->parent() != nullptr;
    if (plan_row && (*it)->data(0, kFileRole).toString() == selected_) w_.list->setCurrentItem(*it);
  }
}

const ops::PracticePlanSummary* LearnersTab::selectedPlan() const {
  for (const auto& p : plans_) {
    if (qs(p.file.string()) == selected_) return &p;
  }
  return nullptr;
}

std::optional<session::Learner> LearnersTab::selectedLearner() const {
  const auto* picked = selectedPlan();
  if (picked == nullptr) return std::nullopt;
  std::optional<session::Learner> latest;
  for (const auto& p : plans_) {
    if (p.learner.code == picked->learner.code) latest = p.learner;
  }
  return latest;
}

void LearnersTab::refreshButtons() {
  const bool picked = selectedPlan() != nullptr;
  w_.new_plan->setEnabled(picked);
  w_.continue_plan->setEnabled(picked && selectedPlan()->schedule.timing != session::SubjectSchedule::Timing::kDone);
  w_.print->setEnabled(progress_.has_value());
}

bool LearnersTab::newLearner() {
  // The form stays open until the learner can be kept: a new code, the rules of learnerProblems.
  LearnerDialog dialog([this](const session::Learner& learner) {
    std::vector<std::string> problems = session::learnerProblems(learner);
    for (const auto& p : plans_) {
      if (p.learner.code == learner.code) {
        problems.push_back("code \"" + learner.code + "\": a learner has it already; pick them and make a new plan");
        break;
      }
    }
    return problems;
  }, this);
  if (dialog.exec() != QDialog::Accepted) return false;
  return askPlan(dialog.learner());
}

bool LearnersTab::newPlan() {
  const auto learner = selectedLearner();
  return learner && askPlan(*learner);
}

bool LearnersTab::askPlan(const session::Learner& learner) {
  // The form stays open until the plan can be made (ops::practicePlanStudy's problems).
  PlanDialog plan(learner, [](const ops::PracticePlanOptions& options) {
    try {
      (void)ops::practicePlanStudy(options);
    } catch (const InputError& e) {
      return splitProblems(e.what());
    }
    return std::vector<std::string>{};
  }, this);
  if (plan.exec() != QDialog::Accepted) return false;
  return createPlan(plan.options());
}

bool LearnersTab::createPlan(const ops::PracticePlanOptions& options) {
  std::filesystem::path file;
  try {
    file = ops::createPracticePlan(folder_.toStdString(), options);
  } catch (const std::exception& e) {
    host_.error(tr("The plan was not made"), what(e));
    return false;
  }
  host_.note(tr("Plan made: %1").arg(qs(file.string())), 8000);
  selected_ = qs(file.string());
  refresh();
  return true;
}

bool LearnersTab::selectPlan(const QString& file) {
  selected_ = file;
  if (selectedPlan() == nullptr) {
    selected_.clear();
    progress_.reset();
    refreshButtons();
    return false;
  }
  markPicked();
  return showProgress();
}

bool LearnersTab::showProgress() {
  const auto* plan = selectedPlan();
  if (plan == nullptr) return false;
  try {
    const auto db = session::StudyDatabase::open(plan->file, session::OpenMode::kReadOnly);
    // Scores already computed are kept per plan: a trial is scored once.
    report::ScoreCache& cache = scores_[plan->file.string()];
    progress_ = report::learnerProgress(db, "", &cache);
    for (const auto& t : progress_->trials) cache.emplace(t.trial_id, t.score);
  } catch (const std::exception& e) {
    progress_.reset();
    host_.error(tr("The progress cannot be read"), what(e));
    refreshButtons();
    return false;
  }
  w_.summary->setText(tr("%1 · %2 · next: %3").arg(learnerTitle(plan->learner), planLine(*plan), qs(progress_->next)));
  w_.sessions->setHtml(qs(report::progressPageHtml(*progress_, {.identified = true, .whole_page = false})));
  w_.curve->setTrials(progress_->trials, progress_->compares_alone);
  refreshButtons();
  return true;
}

bool LearnersTab::continuePlan() {
  const auto* plan = selectedPlan();
  if (plan == nullptr) return false;
  return host_.continue_plan(qs(plan->file.string()), qs(plan->learner.code));
}

bool LearnersTab::printProgress(const QString& file) {
  if (!progress_) return false;
  QString target = file;
  if (target.isEmpty()) {
    target = host_.ask_save_file(tr("Save the progress page"),
                                 QDir(folder_).filePath(qs(progress_->learner.code + "-progress.html")));
    if (target.isEmpty()) return false;
  }
  try {
    writeFileAtomically(target.toStdString(),
                        report::progressPageHtml(*progress_, {.identified = true, .printed = session::localToday().iso()}),
                        Overwrite::kReplace);
  } catch (const Error& e) {
    host_.error(tr("The page was not saved"), what(e));
    return false;
  }
  host_.note(tr("Saved %1: print it from the browser").arg(target), 8000);
  (void)host_.open_url(QUrl::fromLocalFile(target));
  return true;
}

}  // namespace hattr::studio
