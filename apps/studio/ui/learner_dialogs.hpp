#pragma once
/// The Learners tab's two forms: a new learner (code, name, age, handedness, notes) and a new
/// practice plan for one (letters, strategy by its plain name, sessions, trials). Each gathers
/// what the teacher types and stays open, the problems listed in it, until its check finds
/// none, so nothing typed is lost; the tab then makes the plan (ops::createPracticePlan). The
/// widgets are public, so a test fills them in as a person would. GUI thread only.

#include <QDialog>
#include <functional>
#include <string>
#include <vector>

#include "hattr/ops/practice_plan.hpp"

class QComboBox;
class QDialogButtonBox;
class QLineEdit;
class QPlainTextEdit;
class QSpinBox;
class QDoubleSpinBox;
class QLabel;

namespace hattr::studio {

/// A form's check: the problems of what was typed, one a line (none: it may close).
template <class T>
using FormCheck = std::function<std::vector<std::string>(const T&)>;

class LearnerDialog final : public QDialog {
  Q_OBJECT

 public:
  explicit LearnerDialog(FormCheck<session::Learner> check, QWidget* parent = nullptr);
  /// Closes only when the check finds no problem; else lists them in the form.
  void accept() override;
  /// The learner as typed (age 0: not given; handedness "" when not known).
  [[nodiscard]] session::Learner learner() const;

  struct Widgets {
    QLineEdit* code = nullptr;
    QLineEdit* name = nullptr;
    QSpinBox* age = nullptr;
    QComboBox* handedness = nullptr;
    QPlainTextEdit* notes = nullptr;
    QLabel* problems = nullptr;
    QDialogButtonBox* buttons = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  FormCheck<session::Learner> check_;
  Widgets w_;
};

class PlanDialog final : public QDialog {
  Q_OBJECT

 public:
  /// A plan for `learner` (shown, not edited).
  PlanDialog(const session::Learner& learner, FormCheck<ops::PracticePlanOptions> check, QWidget* parent = nullptr);
  /// Closes only when the check finds no problem; else lists them in the form.
  void accept() override;
  /// The plan as typed, for the learner given.
  [[nodiscard]] ops::PracticePlanOptions options() const;

  struct Widgets {
    QLineEdit* letters = nullptr;  ///< "a b c" or "a, b": characters, glyph names or files
    QComboBox* strategy = nullptr;  ///< plain names; the technical name in the tooltip
    QSpinBox* sessions = nullptr;
    QSpinBox* trials = nullptr;
    QSpinBox* checks = nullptr;
    QSpinBox* days_between = nullptr;
    QSpinBox* retention_days = nullptr;
    QDoubleSpinBox* rest_s = nullptr;
    QLabel* problems = nullptr;
    QDialogButtonBox* buttons = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  session::Learner learner_;
  FormCheck<ops::PracticePlanOptions> check_;
  Widgets w_;
};

/// The letters a teacher typed: split at spaces and commas.
[[nodiscard]] std::vector<std::string> splitLetters(const QString& text);
/// The lines of a problem list as the library words it ("practice plan: 2 problems:\n  - a\n
/// - b" -> {"a", "b"}); a message without a list is one line.
[[nodiscard]] std::vector<std::string> splitProblems(const std::string& message);

}  // namespace hattr::studio
