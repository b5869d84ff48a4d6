#pragma once
/// The Train tab's window onto a profile library (docs/library.md): its persons by skill, with
/// their genuine recordings and imitations; a person's template (DBA of their genuine
/// recordings) chosen as the training reference; and a profile's nearest persons (the last trial
/// or a profile file, identified over a feature set, exactly as `hattr library identify`). The
/// library is opened read-only and nothing in it changes. The widgets are public, so a test uses
/// the dialog as a person would. GUI thread only.

#include <QDialog>
#include <QString>
#include <functional>
#include <string>
#include <vector>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/library/matching.hpp"
#include "hattr/library/profile_library.hpp"

class QComboBox;
class QDialogButtonBox;
class QLabel;
class QPushButton;
class QSpinBox;
class QTreeWidget;

namespace hattr::studio {

/// What the dialog may ask of the window: a profile file to open (empty: none chosen).
using AskOpenFile = std::function<QString(const QString& title, const QString& filter)>;

class LibraryDialog final : public QDialog {
  Q_OBJECT

 public:
  /// Over the library at `location` (a file or a postgresql:// address); `last_trial` is the
  /// studio's last trial (null: none). Throws InputError when it is not a library.
  LibraryDialog(const QString& location, const HapticProfile* last_trial, AskOpenFile ask_open_file,
                QWidget* parent = nullptr);

  /// The chosen person's template as a reference, "library:LOCATION#PERSON/SKILL" (empty: no
  /// person chosen).
  [[nodiscard]] QString reference() const;
  /// The nearest persons to the chosen profile for the skill, into the list (false: the problem
  /// is shown in the dialog).
  bool findNearest();
  /// The last search's answer, nearest first.
  [[nodiscard]] const std::vector<library::RankedPerson>& nearest() const { return nearest_; }

  struct Widgets {
    QLabel* location = nullptr;
    QComboBox* skill = nullptr;      ///< the library's skills
    QTreeWidget* persons = nullptr;  ///< person, genuine recordings, imitations (of the skill)
    QComboBox* query = nullptr;      ///< "the last trial" (when there is one) or "a profile file…"
    QComboBox* features = nullptr;   ///< the feature sets, shape+force first
    QSpinBox* top = nullptr;
    QPushButton* find = nullptr;
    QTreeWidget* nearest = nullptr;  ///< rank, person, distance, their nearest entry
    QLabel* problems = nullptr;
    QDialogButtonBox* buttons = nullptr;  ///< Ok: "Train against the template"
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  void buildUi();
  void showPersons();
  void showProblem(const QString& text);
  void refreshButtons();

  std::string location_;
  const HapticProfile* last_trial_;
  AskOpenFile ask_open_file_;
  std::vector<library::LibraryEntry> entries_;  // every entry's labels (not its samples)
  std::vector<library::RankedPerson> nearest_;
  Widgets w_;
};

}  // namespace hattr::studio
