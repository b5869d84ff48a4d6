#include "ui/library_dialog.hpp"

#include <QComboBox>
#include <QDialogButtonBox>
#include <QFormLayout>
#include <QGroupBox>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QRegularExpression>
#include <QSpinBox>
#include <QTreeWidget>
#include <QVBoxLayout>
#include <map>
#include <set>

#include "hattr/io/profile_csv.hpp"
#include "hattr/library/matching.hpp"
#include "hattr/ops/library.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

namespace {

constexpr int kLastTrial = 0, kProfileFile = 1;  // the query choice's data

QTreeWidget* table(const QStringList& headers) {
  auto* t = new QTreeWidget;
  t->setHeaderLabels(headers);
  t->setRootIsDecorated(false);
  t->setUniformRowHeights(true);
  t->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  return t;
}

}  // namespace

LibraryDialog::LibraryDialog(const QString& location, const HapticProfile* last_trial, AskOpenFile ask_open_file,
                             QWidget* parent)
    : QDialog(parent), location_(location.toStdString()), last_trial_(last_trial), ask_open_file_(std::move(ask_open_file)) {
  // Read once: the labels of every entry (the samples stay in the library until a template or a
  // search needs them).
  entries_ = library::ProfileLibrary::open(location_, true).list();
  buildUi();
  showPersons();
}

void LibraryDialog::buildUi() {
  setWindowTitle(tr("Profile library"));
  auto* layout = new QVBoxLayout(this);
  w_.location = wrappedLabel(tr("Library <b>%1</b>: %2 profiles").arg(qs(location_).toHtmlEscaped()).arg(entries_.size()));
  layout->addWidget(w_.location);

  // The skill, and its persons: pick one to train against their template.
  w_.skill = new QComboBox;
  std::set<std::string> skills;
  for (const auto& e : entries_) skills.insert(e.labels.skill);
  for (const auto& s : skills) w_.skill->addItem(qs(s), qs(s));
  auto* form = new QFormLayout;
  form->addRow(tr("Skill"), w_.skill);
  layout->addLayout(form);
  w_.persons = table({tr("Person"), tr("Genuine recordings"), tr("Imitations")});
  w_.persons->setToolTip(tr("A person's template is the average of their genuine recordings (DTW barycenter averaging)"));
  layout->addWidget(w_.persons, 1);
  connect(w_.skill, &QComboBox::currentIndexChanged, this, [this] { showPersons(); });
  connect(w_.persons, &QTreeWidget::itemSelectionChanged, this, [this] { refreshButtons(); });

  // A profile's nearest persons among the skill's genuine recordings.
  auto* search = new QGroupBox(tr("Nearest persons"));
  auto* search_form = new QFormLayout(search);
  w_.query = new QComboBox;
  if (last_trial_ != nullptr) w_.query->addItem(tr("The last trial"), kLastTrial);
  w_.query->addItem(tr("A profile file…"), kProfileFile);
  w_.features = new QComboBox;
  for (const library::FeatureSet set : library::reportedFeatureSets()) w_.features->addItem(qs(set.name()), qs(set.name()));
  w_.features->setCurrentIndex(std::max(0, w_.features->findData(QStringLiteral("shape+force"))));
  w_.top = new QSpinBox;
  w_.top->setRange(1, 50);
  w_.top->setValue(5);
  w_.find = new QPushButton(tr("Find the nearest persons"));
  connect(w_.find, &QPushButton::clicked, this, [this] { findNearest(); });
  w_.nearest = table({tr("Rank"), tr("Person"), tr("Distance"), tr("Their nearest recording")});
  search_form->addRow(tr("Profile"), w_.query);
  search_form->addRow(tr("Features"), w_.features);
  search_form->addRow(tr("Persons"), w_.top);
  search_form->addRow(QString(), w_.find);
  search_form->addRow(w_.nearest);
  layout->addWidget(search, 1);

  w_.problems = wrappedLabel();
  w_.problems->setStyleSheet(QStringLiteral("color: #b00020"));
  w_.problems->hide();
  layout->addWidget(w_.problems);
  w_.buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  w_.buttons->button(QDialogButtonBox::Ok)->setText(tr("Train against the template"));
  connect(w_.buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(w_.buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  layout->addWidget(w_.buttons);
  resize(620, 640);
}

// The skill's persons with their counts of genuine recordings and of imitations of them.
void LibraryDialog::showPersons() {
  const std::string skill = w_.skill->currentData().toString().toStdString();
  std::map<std::string, std::pair<int, int>> counts;
  for (const auto& e : entries_) {
    if (e.labels.skill != skill) continue;
    auto& [genuine, imitations] = counts[e.labels.person];
    ++(e.labels.authenticity == library::Authenticity::kGenuine ? genuine : imitations);
  }
  w_.persons->clear();
  for (const auto& [person, c] : counts) {
    auto* row = new QTreeWidgetItem(w_.persons, QStringList{qs(person), QString::number(c.first), QString::number(c.second)});
    row->setData(0, Qt::UserRole, qs(person));
  }
  refreshButtons();
}

void LibraryDialog::refreshButtons() {
  // A template needs two genuine recordings (buildTemplate's rule), and a person and skill that
  // library:PATH#PERSON/SKILL can name (no '#' or '/' in them), said before it is tried.
  const auto selected = w_.persons->selectedItems();
  const bool enough = !selected.empty() && selected.front()->text(1).toInt() >= 2;
  const QString skill = w_.skill->currentData().toString();
  const bool nameable = selected.empty() || (!selected.front()->text(0).contains(QRegularExpression("[#/]")) &&
                                             !skill.contains('#'));
  w_.buttons->button(QDialogButtonBox::Ok)->setEnabled(enough && nameable);
  w_.buttons->button(QDialogButtonBox::Ok)->setToolTip(
      selected.empty() || (enough && nameable) ? QString()
      : !enough ? tr("a template needs at least 2 genuine recordings")
                : tr("a person or skill with '#' or '/' in its name cannot be named as library:PATH#PERSON/SKILL"));
  w_.find->setEnabled(w_.skill->count() > 0);
}

QString LibraryDialog::reference() const {
  const auto selected = w_.persons->selectedItems();
  if (selected.empty()) return {};
  return QStringLiteral("library:%1#%2/%3")
      .arg(qs(location_), selected.front()->data(0, Qt::UserRole).toString(), w_.skill->currentData().toString());
}

void LibraryDialog::showProblem(const QString& text) {
  w_.problems->setText(text.toHtmlEscaped());
  w_.problems->setVisible(!text.isEmpty());
}

bool LibraryDialog::findNearest() {
  showProblem({});
  w_.nearest->clear();
  nearest_.clear();
  try {
    // The profile: the last trial, or a file the person picks.
    HapticProfile file_profile;
    const HapticProfile* query = last_trial_;
    if (w_.query->currentData().toInt() == kProfileFile) {
      const QString file = ask_open_file_(tr("A profile to identify"), tr("Haptic profiles (*.csv);;All files (*)"));
      if (file.isEmpty()) return false;
      file_profile = io::readProfileCsv(file.toStdString());
      query = &file_profile;
    }
    ops::IdentifyOptions o;
    o.skill = w_.skill->currentData().toString().toStdString();
    o.set = library::parseFeatureSet(w_.features->currentData().toString().toStdString());
    o.top = static_cast<std::size_t>(w_.top->value());
    nearest_ = ops::libraryIdentify(location_, *query, o).ranked;
  } catch (const std::exception& e) {
    showProblem(what(e));
    return false;
  }
  for (std::size_t k = 0; k < nearest_.size(); ++k) {
    const auto& r = nearest_[k];
    new QTreeWidgetItem(w_.nearest, QStringList{QString::number(k + 1), qs(r.person), QString::number(r.distance, 'f', 4), qs(r.key)});
  }
  return true;
}

}  // namespace hattr::studio
