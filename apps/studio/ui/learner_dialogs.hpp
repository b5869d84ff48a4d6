#pragma once
/// The Learners tab's two forms: a new learner (code, name, age, handedness, notes) and a new
/// practice plan for one (letters, strategy by its plain name, sessions, trials). Each only
/// gathers what the teacher types; the tab makes the plan (ops::createPracticePlan) and shows
/// any problem. The widgets are public, so a test fills them in as a person would.
/// GUI thread only.

#include <QDialog>

#include "hattr/ops/practice_plan.hpp"

class QComboBox;
class QDialogButtonBox;
class QLineEdit;
class QPlainTextEdit;
class QSpinBox;
class QDoubleSpinBox;

namespace hattr::studio {

class LearnerDialog final : public QDialog {
  Q_OBJECT

 public:
  explicit LearnerDialog(QWidget* parent = nullptr);
  /// The learner as typed (age 0: not given; handedness "" when not known).
  [[nodiscard]] session::Learner learner() const;

  struct Widgets {
    QLineEdit* code = nullptr;
    QLineEdit* name = nullptr;
    QSpinBox* age = nullptr;
    QComboBox* handedness = nullptr;
    QPlainTextEdit* notes = nullptr;
    QDialogButtonBox* buttons = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  Widgets w_;
};

class PlanDialog final : public QDialog {
  Q_OBJECT

 public:
  /// A plan for `learner` (shown, not edited).
  explicit PlanDialog(const session::Learner& learner, QWidget* parent = nullptr);
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
    QDialogButtonBox* buttons = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  session::Learner learner_;
  Widgets w_;
};

/// The letters a teacher typed: split at spaces and commas.
[[nodiscard]] std::vector<std::string> splitLetters(const QString& text);

}  // namespace hattr::studio
