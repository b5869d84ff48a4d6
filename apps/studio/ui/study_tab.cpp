#include "ui/study_tab.hpp"

#include <QComboBox>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>
#include <cmath>

#include "hattr/session/study_schedule.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

StudyTab::StudyTab(QSettings& settings, StudyHost host, QWidget* parent)
    : QWidget(parent), settings_(settings), host_(std::move(host)) {
  buildUi();
}

StudyTab::~StudyTab() = default;

// ---- Construction ------------------------------------------------------------------------

void StudyTab::buildUi() {
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(
      wrappedLabel(tr("<b>Study session</b> for a person: open a study database (made with "
                      "<tt>hattr study init</tt>), pick the subject and follow the prompts. Every "
                      "trial is stored the moment it ends; reopening resumes where it stopped.")));
  auto* open_button = new QPushButton(tr("Open study… (Ctrl+D)"));
  connect(open_button, &QPushButton::clicked, this, [this] {
    const QString file =
        host_.ask_open_file(tr("Open a study database"), tr("Study databases (*.sqlite *.db);;All files (*)"));
    if (!file.isEmpty()) open(file);
  });
  layout->addWidget(open_button);
  w_.study = wrappedLabel(tr("No study open."));
  layout->addWidget(w_.study);

  // The subject picker.
  auto* row = new QHBoxLayout;
  w_.subject = new QComboBox;
  w_.subject->setObjectName(QStringLiteral("study_subject"));
  w_.begin = new QPushButton(tr("Begin"));
  connect(w_.begin, &QPushButton::clicked, this, [this] { selectSubject(w_.subject->currentData().toString()); });
  row->addWidget(new QLabel(tr("Subject")));
  row->addWidget(w_.subject, 1);
  row->addWidget(w_.begin);
  layout->addLayout(row);

  // The progress and the prompt, large: the subject reads it from a distance.
  w_.progress = wrappedLabel();
  layout->addWidget(w_.progress);
  w_.prompt = wrappedLabel();
  QFont big = w_.prompt->font();
  big.setPointSizeF(big.pointSizeF() * 1.3);
  big.setBold(true);
  w_.prompt->setFont(big);
  w_.prompt->setObjectName(QStringLiteral("study_prompt"));
  layout->addWidget(w_.prompt);

  // One button starts the next trial or stops the running one.
  w_.next = new QPushButton(tr("Start trial (Space) / skip rest (N)"));
  w_.next->setObjectName(QStringLiteral("study_next"));
  connect(w_.next, &QPushButton::clicked, this, [this] {
    if (host_.trial_running()) {
      host_.stop_trial();
    } else {
      next();
    }
  });
  layout->addWidget(w_.next);
  w_.close = new QPushButton(tr("Close study"));
  connect(w_.close, &QPushButton::clicked, this, &StudyTab::closeStudy);
  layout->addWidget(w_.close);
  w_.scores = wrappedLabel();
  layout->addWidget(w_.scores);
  layout->addStretch(1);
}

// ---- Actions ------------------------------------------------------------------------------

bool StudyTab::open(const QString& file) {
  if (!host_.idle()) {
    host_.error(tr("A study cannot be opened now"), tr("finish the trial or recording first"));
    return false;
  }
  std::unique_ptr<StudySession> session;
  try {
    session = std::make_unique<StudySession>(file.toStdString());
  } catch (const std::exception& e) {
    host_.error(tr("The study could not be opened"), what(e));
    return false;
  }
  closeStudy();
  study_ = std::move(session);
  settings_.setValue("study/file", file);
  const session::StudyDefinition& study = study_->study();
  if (session::isPaperDesign(study)) {
    w_.study->setText(tr("<b>%1</b> (%2): skill %3, %4 training + %5 recall trials per mode, rest %6 s")
                          .arg(qs(study.name).toHtmlEscaped(), QFileInfo(file).fileName().toHtmlEscaped(),
                               qs(study.skill).toHtmlEscaped())
                          .arg(study.protocol.training_trials)
                          .arg(study.protocol.recall_trials)
                          .arg(study.protocol.rest_s));
  } else {
    w_.study->setText(tr("<b>%1</b> (%2): %n session(s) over %3 day(s), ", nullptr,
                         static_cast<int>(study.schedule.size()))
                          .arg(qs(study.name).toHtmlEscaped(), QFileInfo(file).fileName().toHtmlEscaped())
                          .arg(study.schedule.back().day + 1) +
                      tr("%n group(s)", nullptr, static_cast<int>(study.groups.size())));
  }
  fillSubjects();
  // Nothing of the tab used before stays on show: a reviewed trial (orange), a take, a playback.
  host_.clear_views();
  host_.use_environment(&study_->environment());
  host_.show_reference(nullptr, false);
  refreshPanel();
  host_.changed();
  return true;
}

void StudyTab::fillSubjects() {
  w_.subject->clear();
  if (!study_) return;
  // Each subject with where they stand: the next session for S07, due today, early or overdue.
  for (const session::SubjectRecord& s : study_->subjects()) {
    w_.subject->addItem(tr("%1 (%2): %3").arg(qs(s.id), qs(s.spec.participant),
                                               qs(session::scheduleText(study_->schedule(s.id)))),
                        qs(s.id));
  }
}

bool StudyTab::selectSubject(const QString& subject) {
  if (!study_ || host_.trial_running()) return false;
  try {
    std::string kind;
    for (const auto& s : study_->subjects()) {
      if (s.id == subject.toStdString()) kind = s.spec.participant;
    }
    if (kind != "person" &&
        !host_.confirm(tr("Subject %1 is a \"%2\" participant, not a person. Run its trials here with the mouse anyway?")
                           .arg(subject, qs(kind)))) {
      return false;
    }
    study_->selectSubject(subject.toStdString(), host_.now_s());
  } catch (const std::exception& e) {
    host_.error(tr("The subject could not be selected"), what(e));
    return false;
  }
  host_.clear_views();
  host_.show_reference(&study_->expert(), false);
  refreshPanel();
  host_.changed();
  return true;
}

bool StudyTab::beginNextSession() {
  const session::SubjectSchedule schedule = study_->schedule();
  if (schedule.timing == session::SubjectSchedule::Timing::kEarly &&
      !host_.confirm(tr("Session %1 of %2 is due on %3, in %n day(s). Begin it early?", nullptr, schedule.days_off)
                         .arg(schedule.session + 1)
                         .arg(schedule.sessions)
                         .arg(qs(schedule.due->iso())))) {
    return false;
  }
  study_->beginNextSession();
  refreshPanel();
  host_.changed();
  return true;
}

bool StudyTab::next() {
  if (!study_ || !host_.idle()) return false;
  const auto state = study_->state();
  if (state == StudySession::State::kNextSession) return beginNextSession();
  if (state != StudySession::State::kReady && state != StudySession::State::kResting) return false;
  try {
    const bool shows_reference = study_->currentTrial()->plan.view.show_reference;
    session::TrialSetup setup = study_->currentSetup();
    setup.settle_s = host_.settle_s();  // the person's "get ready" (not recorded)
    study_->beginTrial();
    try {
      host_.start_trial(study_->environment(), setup, study_->expert(), shows_reference, promptText(), w_.scores);
    } catch (...) {
      study_->abandonTrial();
      throw;
    }
  } catch (const std::exception& e) {
    host_.error(tr("The study trial could not start"), what(e));
    return false;
  }
  refreshPanel();
  host_.changed();
  return true;
}

void StudyTab::closeStudy() {
  if (!study_ || host_.device_busy()) return;
  host_.use_environment(nullptr);  // the rig runs on the study's paper: it moves before the study goes
  study_.reset();
  w_.subject->clear();
  w_.study->setText(tr("No study open."));
  refreshPanel();
  host_.changed();
}

// ---- A trial's end ------------------------------------------------------------------------

void StudyTab::trialFailed(const std::string& failure) {
  std::string message = failure;
  try {
    study_->failTrial(failure);  // marked failed, as the study runner marks it
  } catch (const std::exception& e) {
    study_->abandonTrial();
    message += "\n\n" + std::string(e.what());
  }
  w_.scores->setText(tr("The trial failed; it runs again."));
  refreshPanel();
  host_.error(tr("The trial failed"),
              qs(message) + tr("\n\nIt is not kept (marked failed in the study database); Next runs it again."));
}

void StudyTab::trialAbandoned() {
  study_->abandonTrial();
  w_.scores->setText(tr("Nothing kept; this trial runs again."));
  refreshPanel();
}

StudyTab::Stored StudyTab::trialEnded(session::TrialResult result) {
  Stored out;
  try {
    const std::string disturbed = study_->completeTrial(std::move(result), host_.now_s());
    out.stored = true;
    const bool again = !disturbed.empty() && study_->state() == StudySession::State::kReady;
    host_.note(again ? tr("The trial was disturbed (%1): it is kept, and runs again.").arg(qs(disturbed))
               : disturbed.empty() ? tr("Trial stored in the study database.")
                                   : tr("Trial stored, flagged as disturbed (%1).").arg(qs(disturbed)),
               8000);
  } catch (const std::exception& e) {
    host_.error(tr("The trial could not be stored in the study database"),
                what(e) + tr("\n\nIt is also still the last trial: File → Save last trial… (Ctrl+Shift+S) "
                             "saves it where you choose. The study runs this trial again."));
  }
  refreshPanel();
  // The subject sees no score during a study unless the study file asks (the paper showed none).
  out.show_scores = study_->study().protocol.show_scores;
  if (!out.show_scores) w_.scores->setText(tr("Trial stored. No score is shown during the study (protocol.show_scores)."));
  return out;
}

// ---- What the subject sees ------------------------------------------------------------------

void StudyTab::setEngineerView(bool on) {
  engineer_view_ = on;
  refreshPanel();
}

QString StudyTab::promptText() const {
  using Wording = session::SubjectTrials::Wording;
  return qs(study_->prompt(engineer_view_ ? Wording::kTechnical : Wording::kPlain));
}

QString StudyTab::idleBanner() {
  if (!study_ || study_->state() == StudySession::State::kNoSubject) return {};
  const double now = host_.now_s();
  study_->tick(now);
  QString banner;
  switch (study_->state()) {
    case StudySession::State::kResting:
      banner = tr("Rest: %1 s").arg(std::ceil(study_->restRemaining_s(now)), 0, 'f', 0);
      break;
    case StudySession::State::kReady: banner = promptText() + tr(" — Space to start"); break;
    case StudySession::State::kNextSession: banner = promptText(); break;
    case StudySession::State::kFinished: banner = tr("Every trial is done. Thank you!"); break;
    default: break;
  }
  refreshPanel();
  return banner;
}

void StudyTab::refreshPanel() {
  if (!study_) {
    w_.progress->clear();
    w_.prompt->clear();
    refresh();
    return;
  }
  const auto state = study_->state();
  w_.progress->setText(state == StudySession::State::kNoSubject ? tr("Pick a subject and press Begin.")
                                                                : tr("Subject %1: %2 of %3 trials done (%4)")
                                                                      .arg(qs(study_->subject()))
                                                                      .arg(study_->completedCount())
                                                                      .arg(study_->totalCount())
                                                                      .arg(qs(stateName(state))));
  QString prompt = promptText();
  if (state == StudySession::State::kResting) {
    prompt = tr("Rest %1 s, then: %2").arg(std::ceil(study_->restRemaining_s(host_.now_s())), 0, 'f', 0).arg(prompt);
  }
  if (const session::TrialRecord* t = study_->currentTrial();
      t != nullptr && state != StudySession::State::kFinished && state != StudySession::State::kNextSession) {
    prompt += t->plan.view.show_reference ? tr("<br><small>the reference is shown</small>")
                                          : tr("<br><small>from memory: the reference is hidden</small>");
    // Recall is recall: the reference is gone from the moment its trial is announced, rest included.
    if (!t->plan.view.show_reference && !host_.trial_running()) host_.hide_reference();
  }
  w_.prompt->setText(prompt);
  refresh();
}

void StudyTab::refresh() {
  const bool open = study_ != nullptr;
  const bool running = host_.trial_running();
  w_.subject->setEnabled(open && !running);
  w_.begin->setEnabled(open && !running);
  w_.close->setEnabled(open && !host_.device_busy());
  const bool between = open && study_->state() == StudySession::State::kNextSession;
  QString next_text = running ? tr("Stop trial (Ctrl+.)") : tr("Start trial (Space) / skip rest (N)");
  if (between) {
    const session::SubjectSchedule schedule = study_->schedule();
    next_text = schedule.timing == session::SubjectSchedule::Timing::kEarly
                    ? tr("Begin session %1 early (due %2)").arg(schedule.session + 1).arg(qs(schedule.due->iso()))
                    : tr("Begin session %1").arg(schedule.session + 1);
  }
  w_.next->setText(next_text);
  const bool next_step = open && (study_->state() == StudySession::State::kReady ||
                                  study_->state() == StudySession::State::kResting || between);
  w_.next->setEnabled(open && (running || (host_.idle() && next_step)));
}

}  // namespace hattr::studio
