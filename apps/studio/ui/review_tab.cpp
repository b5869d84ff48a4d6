#include "ui/review_tab.hpp"

#include <QApplication>
#include <QComboBox>
#include <QDir>
#include <QEventLoop>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QSignalBlocker>
#include <QTreeWidget>
#include <QTreeWidgetItemIterator>
#include <QUrl>
#include <QVBoxLayout>

#include <atomic>
#include <string>
#include <system_error>
#include <thread>

#include "core/study_report_export.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

/// The wait cursor while a slow call runs on the GUI thread.
struct WaitCursor {
  WaitCursor() { QApplication::setOverrideCursor(Qt::WaitCursor); }
  ~WaitCursor() { QApplication::restoreOverrideCursor(); }
  WaitCursor(const WaitCursor&) = delete;
  WaitCursor& operator=(const WaitCursor&) = delete;
};

}  // namespace

ReviewTab::ReviewTab(QSettings& settings, ReviewHost host, QWidget* parent)
    : QWidget(parent), settings_(settings), host_(std::move(host)) {
  buildUi();
}

ReviewTab::~ReviewTab() = default;

// ---- Construction ------------------------------------------------------------------------

void ReviewTab::buildUi() {
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(
      wrappedLabel(tr("<b>Review</b> a study: pick a completed trial to overlay it on the expert "
                      "(orange on blue) and play it back.")));
  auto* open_button = new QPushButton(tr("Open study for review… (Ctrl+Shift+D)"));
  connect(open_button, &QPushButton::clicked, this, [this] {
    const QString file =
        host_.ask_open_file(tr("Open a study database for review"), tr("Study databases (*.sqlite *.db);;All files (*)"));
    if (!file.isEmpty()) open(file);
  });
  layout->addWidget(open_button);
  w_.study = wrappedLabel(tr("No study open for review."));
  layout->addWidget(w_.study);

  // The subjects and their trials; a completed trial carries its database id.
  w_.tree = new QTreeWidget;
  w_.tree->setHeaderLabels({tr("Trial"), tr("Mode"), tr("Phase"), tr("Shape"), tr("Force"), tr("Status")});
  w_.tree->headerItem()->setToolTip(kShape, tr("recall trials: DTW cost of x + y against the expert (lower is closer)"));
  w_.tree->headerItem()->setToolTip(kForce, tr("recall trials: DTW cost of fx + fy + fz against the expert"));
  w_.tree->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  connect(w_.tree, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    if (item != nullptr && item->data(kTrial, Qt::UserRole).isValid()) {
      showTrial(item->data(kTrial, Qt::UserRole).toLongLong());
    }
  });
  layout->addWidget(w_.tree, 1);
  w_.costs = wrappedLabel();
  w_.costs->setObjectName("review_costs");
  layout->addWidget(w_.costs);

  // Playback and the report.
  auto* row = new QHBoxLayout;
  w_.play = new QPushButton(tr("Play / pause (P)"));
  connect(w_.play, &QPushButton::clicked, this, [this] { host_.toggle_playback(); });
  w_.speed = new QComboBox;
  for (const double speed : {0.25, 0.5, 1.0, 2.0}) w_.speed->addItem(tr("%1×").arg(speed), speed);
  w_.speed->setCurrentIndex(2);
  connect(w_.speed, &QComboBox::activated, this, [this] { host_.set_speed(speed()); });
  row->addWidget(w_.play, 1);
  row->addWidget(w_.speed);
  layout->addLayout(row);
  w_.report = new QPushButton(tr("Open report… (Ctrl+Shift+R)"));
  w_.report->setToolTip(tr("Analyze the study (DTW, ANOVA) and open report.html, written next to the database"));
  connect(w_.report, &QPushButton::clicked, this, [this] { (void)openReport(); });
  layout->addWidget(w_.report);
  w_.scores = wrappedLabel();
  w_.scores->setObjectName("review_scores");
  layout->addWidget(w_.scores);
}

double ReviewTab::speed() const { return w_.speed->currentData().toDouble(); }

void ReviewTab::refresh(bool playback_loaded) {
  w_.play->setEnabled(trial_.has_value() || playback_loaded);
  w_.report->setEnabled(db_ != nullptr && !reporting_);
}

// ---- Actions -------------------------------------------------------------------------------

bool ReviewTab::open(const QString& file) {
  if (reporting_) {
    host_.error(tr("The study could not be opened for review"), tr("a report is being written; wait for it"));
    return false;
  }
  std::unique_ptr<session::StudyDatabase> db;
  try {
    db = std::make_unique<session::StudyDatabase>(
        session::StudyDatabase::open(file.toStdString(), session::OpenMode::kReadOnly));
  } catch (const std::exception& e) {
    host_.error(tr("The study could not be opened for review"), what(e));
    return false;
  }
  // The previous study's trial, expert and scores go with it (a playback held a pointer to it).
  host_.forget(trial());
  trial_.reset();
  expert_.reset();
  w_.scores->clear();
  db_ = std::move(db);
  file_ = file;
  settings_.setValue("review/file", file);
  w_.study->setText(tr("<b>%1</b> (%2)")
                        .arg(qs(db_->study().name).toHtmlEscaped(), QFileInfo(file).fileName().toHtmlEscaped()));

  // The costs of the analysis stored in the study (`hattr study analyze`), if any.
  try {
    const std::vector<report::TrialCost> stored = report::storedCosts(*db_);
    useCosts(stored, stored.empty() ? tr("No analysis is stored in this study: <i>Open report</i> scores its recall "
                                         "trials.")
                                    : tr("Shape and force: the recall trials' costs in the study's stored analysis."));
  } catch (const std::exception& e) {
    useCosts({}, tr("The study's stored analysis could not be read: %1").arg(what(e).toHtmlEscaped()));
  }
  host_.changed();
  return true;
}

void ReviewTab::useCosts(const std::vector<report::TrialCost>& costs, const QString& source) {
  costs_.clear();
  for (const report::TrialCost& c : costs) costs_.emplace(c.trial_id, c);
  w_.costs->setText(source);
  // The tree anew, the trial on show still selected (without showing it again).
  const QTreeWidgetItem* current = w_.tree->currentItem();
  const QVariant selected = current != nullptr ? current->data(kTrial, Qt::UserRole) : QVariant();
  const QSignalBlocker quiet(w_.tree);
  fillTree();
  if (!selected.isValid()) return;
  for (QTreeWidgetItemIterator it(w_.tree); *it != nullptr; ++it) {
    if ((*it)->data(kTrial, Qt::UserRole) == selected) w_.tree->setCurrentItem(*it);
  }
}

void ReviewTab::fillTree() {
  w_.tree->clear();
  if (!db_) return;
  const auto number = [](double v) { return QString::number(v, 'g', 4); };
  try {
    for (const session::SubjectRecord& subject : db_->subjects()) {
      const std::vector<session::TrialRecord> trials = db_->trials(subject.id);
      int done = 0;
      for (const auto& t : trials) done += t.status == session::TrialStatus::kCompleted ? 1 : 0;
      auto* top = new QTreeWidgetItem(w_.tree, {tr("%1 · %2/%3").arg(qs(subject.id)).arg(done).arg(trials.size()),
                                                qs(subject.spec.participant)});
      top->setToolTip(kTrial, tr("%1: %2 of %3 trials done").arg(qs(subject.id)).arg(done).arg(trials.size()));
      for (const session::TrialRecord& t : trials) {
        // A completed trial is ticked (the narrow panel keeps room for the costs); others say why not.
        const bool completed = t.status == session::TrialStatus::kCompleted;
        auto* item = new QTreeWidgetItem(
            top, {tr("#%1 (%2)").arg(t.plan.sequence + 1).arg(t.plan.index),
                  engineer_view_ ? qs(guidance::modeName(t.plan.mode)) : qs(guidance::strategyInfo(t.plan.mode).plain_name),
                  qs(t.plan.phase)});
        item->setText(kStatus, completed ? QStringLiteral("✓") : qs(session::trialStatusName(t.status)));
        item->setToolTip(kStatus, qs(session::trialStatusName(t.status)));
        if (completed) item->setData(kTrial, Qt::UserRole, QVariant::fromValue<qint64>(t.id));
        if (const auto cost = costs_.find(t.id); cost != costs_.end()) {
          item->setText(kShape, number(cost->second.trajectory()));
          item->setText(kForce, number(cost->second.forceProfile()));
          if (!cost->second.disturbed.empty()) {
            item->setText(kStatus, item->text(kStatus) + tr(" disturbed"));
            item->setToolTip(kStatus, tr("completed, disturbed: %1").arg(qs(cost->second.disturbed)));
          }
        }
      }
    }
    w_.tree->expandAll();
  } catch (const std::exception& e) {
    host_.error(tr("The study's trials could not be read"), what(e));
  }
}

bool ReviewTab::showTrial(qint64 trial_id) {
  if (!db_ || !host_.may_show()) return false;
  // Both read before either replaces what is on show (a playback may be reading it).
  std::optional<HapticProfile> trial;
  std::optional<HapticProfile> expert;
  try {
    trial = db_->trialProfile(trial_id);
    expert = db_->expert(db_->study().skill);
  } catch (const std::exception& e) {
    host_.error(tr("The trial could not be read"), what(e));
    return false;
  }
  trial_ = std::move(trial);
  expert_ = std::move(expert);
  auto& extra = trial_->metadata().extra;
  const QString title = tr("%1, %2 %3 trial %4")
                            .arg(qs(trial_->metadata().subject))
                            .arg(qs(extra["study_mode"]))
                            .arg(qs(extra["phase"]))
                            .arg(qs(extra["trial"]));
  host_.show(*trial_, *expert_, title, w_.scores);
  return true;
}

bool ReviewTab::openReport() {
  if (!db_) {
    host_.error(tr("No study open for review"), tr("open a study for review first (Ctrl+Shift+D)"));
    return false;
  }
  if (reporting_) return false;
  // The report is written off this thread (seconds for a large study), by its own read-only
  // connection; this thread's events go on meanwhile, and the tab's actions wait for it.
  reporting_ = true;
  w_.report->setEnabled(false);
  ReviewReport written;
  std::string failure;
  std::atomic<bool> done{false};
  const std::filesystem::path file_path(file_.toStdString());
  QEventLoop until_written;
  const auto write = [&] {
    try {
      const auto db = session::StudyDatabase::open(file_path, session::OpenMode::kReadOnly);
      written = writeReviewReport(db, file_path);
    } catch (const std::exception& e) {
      failure = e.what();
    }
    done.store(true, std::memory_order_release);
    QMetaObject::invokeMethod(&until_written, &QEventLoop::quit, Qt::QueuedConnection);
  };
  bool quitting = false;
  try {
    std::thread worker(write);
    {
      const WaitCursor wait;
      until_written.exec();
    }
    // The application quitting ends every event loop, ours before the report was done.
    quitting = !done.load(std::memory_order_acquire);
    worker.join();
  } catch (const std::system_error& e) {  // no thread to be had: nothing was written
    failure = e.what();
  }
  reporting_ = false;
  w_.report->setEnabled(db_ != nullptr);
  if (quitting) return false;  // the report is written; nobody is there to see it now
  if (!failure.empty()) {
    host_.error(tr("The report could not be made"), QString::fromStdString(failure));
    return false;
  }
  useCosts(written.costs, tr("Shape and force: the recall trials' costs in the report just written."));
  const QString file = QString::fromStdString(written.html.string());
  host_.note(tr("Report written: %1").arg(QDir::toNativeSeparators(file)));
  if (!host_.open_url(QUrl::fromLocalFile(file))) {
    host_.error(tr("The report could not be opened"), tr("no program opens %1; it was written there").arg(file));
    return false;
  }
  return true;
}

void ReviewTab::setEngineerView(bool on) {
  engineer_view_ = on;
  if (!db_) return;
  const QSignalBlocker quiet(w_.tree);
  fillTree();
}

}  // namespace hattr::studio
