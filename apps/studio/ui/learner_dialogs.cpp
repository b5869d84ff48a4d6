#include "ui/learner_dialogs.hpp"

#include <QComboBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QRegularExpression>
#include <QSpinBox>
#include <QVBoxLayout>

#include "hattr/guidance/strategy_catalog.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

QSpinBox* spin(int lo, int hi, int value, const QString& suffix = {}) {
  auto* box = new QSpinBox;
  box->setRange(lo, hi);
  box->setValue(value);
  box->setSuffix(suffix);
  return box;
}

/// The form's problem list: red, empty until a check finds something.
QLabel* problemList() {
  QLabel* label = wrappedLabel();
  label->setObjectName("form_problems");
  label->setStyleSheet(QStringLiteral("color: #b00020"));
  label->hide();
  return label;
}

/// Shows `problems` in `label`; true when there are none.
bool showProblems(QLabel* label, const std::vector<std::string>& problems) {
  QString text;
  for (const auto& p : problems) text += (text.isEmpty() ? "" : "<br>") + QStringLiteral("• ") + qs(p).toHtmlEscaped();
  label->setText(text);
  label->setVisible(!problems.empty());
  return problems.empty();
}

QDialogButtonBox* okCancel(QDialog* dialog, const QString& ok) {
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  buttons->button(QDialogButtonBox::Ok)->setText(ok);
  QObject::connect(buttons, &QDialogButtonBox::accepted, dialog, &QDialog::accept);
  QObject::connect(buttons, &QDialogButtonBox::rejected, dialog, &QDialog::reject);
  return buttons;
}

}  // namespace

std::vector<std::string> splitProblems(const std::string& message) {
  constexpr std::string_view kItem = "\n  - ";
  std::vector<std::string> lines;
  std::size_t at = message.find(kItem);
  if (at == std::string::npos) return {message};
  while (at != std::string::npos) {
    const std::size_t next = message.find(kItem, at + kItem.size());
    lines.push_back(message.substr(at + kItem.size(), next == std::string::npos ? next : next - at - kItem.size()));
    at = next;
  }
  return lines;
}

std::vector<std::string> splitLetters(const QString& text) {
  std::vector<std::string> out;
  for (const QString& part : text.split(QRegularExpression("[\\s,]+"), Qt::SkipEmptyParts)) {
    out.push_back(part.toStdString());
  }
  return out;
}

LearnerDialog::LearnerDialog(FormCheck<session::Learner> check, QWidget* parent)
    : QDialog(parent), check_(std::move(check)) {
  setWindowTitle(tr("New learner"));
  setObjectName("learner_dialog");
  w_.code = new QLineEdit;
  w_.code->setObjectName("learner_code");
  w_.code->setPlaceholderText(tr("e.g. mia or L01"));
  w_.code->setToolTip(tr("Names the learner's files and, in exports, the learner: letters, digits, - or _"));
  w_.name = new QLineEdit;
  w_.name->setObjectName("learner_name");
  w_.name->setToolTip(tr("Kept in the practice file; left out of exports unless asked for"));
  w_.age = spin(0, 120, 0, tr(" years"));
  w_.age->setObjectName("learner_age");
  w_.age->setSpecialValueText(tr("not given"));
  w_.handedness = new QComboBox;
  w_.handedness->setObjectName("learner_handedness");
  w_.handedness->addItem(tr("not known"), QString());
  w_.handedness->addItem(tr("right-handed"), QStringLiteral("right"));
  w_.handedness->addItem(tr("left-handed"), QStringLiteral("left"));
  w_.handedness->addItem(tr("both"), QStringLiteral("both"));
  w_.notes = new QPlainTextEdit;
  w_.notes->setObjectName("learner_notes");
  w_.notes->setMaximumHeight(80);
  w_.buttons = okCancel(this, tr("Next: a practice plan…"));

  auto* form = new QFormLayout;
  form->addRow(tr("Code"), w_.code);
  form->addRow(tr("Name"), w_.name);
  form->addRow(tr("Age"), w_.age);
  form->addRow(tr("Hand"), w_.handedness);
  form->addRow(tr("Notes"), w_.notes);
  auto* layout = new QVBoxLayout(this);
  layout->addLayout(form);
  layout->addWidget(wrappedLabel(tr("The learner is kept with their first practice plan, made next.")));
  w_.problems = problemList();
  layout->addWidget(w_.problems);
  layout->addWidget(w_.buttons);
}

void LearnerDialog::accept() {
  if (showProblems(w_.problems, check_(learner()))) QDialog::accept();
}

session::Learner LearnerDialog::learner() const {
  session::Learner l{.code = w_.code->text().trimmed().toStdString(),
                     .name = w_.name->text().trimmed().toStdString(),
                     .handedness = w_.handedness->currentData().toString().toStdString(),
                     .notes = w_.notes->toPlainText().trimmed().toStdString()};
  if (w_.age->value() > 0) l.age_years = w_.age->value();
  return l;
}

PlanDialog::PlanDialog(const session::Learner& learner, FormCheck<ops::PracticePlanOptions> check, QWidget* parent)
    : QDialog(parent), learner_(learner), check_(std::move(check)) {
  setWindowTitle(tr("New practice plan"));
  setObjectName("plan_dialog");
  const ops::PracticePlanOptions defaults;
  w_.letters = new QLineEdit;
  w_.letters->setObjectName("plan_letters");
  w_.letters->setPlaceholderText(tr("e.g. a  or  a b c  or  A 7"));
  w_.letters->setToolTip(tr("Letters a–z, A–Z and digits 0–9 of hattr's print script, one or more"));
  w_.strategy = new QComboBox;
  w_.strategy->setObjectName("plan_strategy");
  for (const auto& info : guidance::strategyCatalog()) {
    if (info.mentored) continue;  // a live expert: not for a practice plan
    w_.strategy->addItem(qs(info.plain_name), static_cast<int>(info.mode));
    w_.strategy->setItemData(w_.strategy->count() - 1,
                             qs(guidance::modeName(info.mode)) + ": " + qs(info.description), Qt::ToolTipRole);
  }
  w_.strategy->setCurrentIndex(w_.strategy->findData(static_cast<int>(defaults.strategy)));
  w_.sessions = spin(1, 60, defaults.sessions);
  w_.sessions->setObjectName("plan_sessions");
  w_.trials = spin(1, 100, defaults.trials_per_session);
  w_.trials->setObjectName("plan_trials");
  w_.checks = spin(0, 20, defaults.check_trials);
  w_.checks->setObjectName("plan_checks");
  w_.days_between = spin(0, 30, defaults.days_between, tr(" days"));
  w_.days_between->setObjectName("plan_days_between");
  w_.retention_days = spin(0, 90, defaults.retention_after_days, tr(" days later"));
  w_.retention_days->setObjectName("plan_retention_days");
  w_.retention_days->setSpecialValueText(tr("no later check"));
  w_.rest_s = new QDoubleSpinBox;
  w_.rest_s->setObjectName("plan_rest");
  w_.rest_s->setRange(0.0, 600.0);
  w_.rest_s->setValue(defaults.rest_s);
  w_.rest_s->setSuffix(tr(" s"));
  w_.buttons = okCancel(this, tr("Make the plan"));

  auto* form = new QFormLayout;
  form->addRow(tr("For"), new QLabel(qs(session::displayName(learner))));
  form->addRow(tr("Letters"), w_.letters);
  form->addRow(tr("Help while practising"), w_.strategy);
  form->addRow(tr("Sessions"), w_.sessions);
  form->addRow(tr("Guided letters a session"), w_.trials);
  form->addRow(tr("Letters written alone a session"), w_.checks);
  form->addRow(tr("Between sessions"), w_.days_between);
  form->addRow(tr("A last check"), w_.retention_days);
  form->addRow(tr("Rest between letters"), w_.rest_s);
  auto* layout = new QVBoxLayout(this);
  layout->addLayout(form);
  layout->addWidget(wrappedLabel(tr("Each session: each letter written with help, then alone from memory. The first "
                                    "session begins with each letter written alone with the model shown.")));
  w_.problems = problemList();
  layout->addWidget(w_.problems);
  layout->addWidget(w_.buttons);
}

void PlanDialog::accept() {
  if (showProblems(w_.problems, check_(options()))) QDialog::accept();
}

ops::PracticePlanOptions PlanDialog::options() const {
  ops::PracticePlanOptions o;
  o.learner = learner_;
  o.letters = splitLetters(w_.letters->text());
  o.strategy = static_cast<guidance::TrainingMode>(w_.strategy->currentData().toInt());
  o.sessions = w_.sessions->value();
  o.trials_per_session = w_.trials->value();
  o.check_trials = w_.checks->value();
  o.days_between = w_.days_between->value();
  o.retention_after_days = w_.retention_days->value();
  o.rest_s = w_.rest_s->value();
  return o;
}

}  // namespace hattr::studio
