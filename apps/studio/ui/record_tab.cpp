#include "ui/record_tab.hpp"

#include <QComboBox>
#include <QFormLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>
#include <algorithm>

#include "core/profile_files.hpp"
#include "hattr/core/error.hpp"
#include "hattr/sim/glyph.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

RecordTab::RecordTab(LiveRig& rig, QSettings& settings, RecordHost host, QWidget* parent)
    : QWidget(parent), rig_(rig), settings_(settings), host_(std::move(host)) {
  buildUi();
  w_.expert->setText(settings_.value("record/name").toString());
  w_.character->setText(settings_.value("record/character").toString());
  w_.trigger->setCurrentIndex(settings_.value("record/trigger", 0).toInt());
  (void)setLetterGuide(settings_.value("record/guide").toString());
}

RecordTab::~RecordTab() = default;

// ---- Construction ------------------------------------------------------------------------

void RecordTab::buildUi() {
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(
      wrappedLabel(tr("<b>Record an expert.</b> Name the expert and the character, then record: "
                      "with the pen-down trigger the take starts when the pen touches the paper and "
                      "ends after it has been lifted for a second.")));
  // Who writes what, and what starts and stops the take.
  auto* form = new QFormLayout;
  w_.expert = new QLineEdit;
  w_.expert->setPlaceholderText(tr("e.g. expert1"));
  w_.character = new QLineEdit;
  w_.character->setPlaceholderText(tr("e.g. na"));
  w_.trigger = new QComboBox;
  w_.trigger->addItem(tr("Pen down starts, 1 s pen-up stops"));
  w_.trigger->addItem(tr("Record / Stop buttons"));
  form->addRow(tr("Expert"), w_.expert);
  form->addRow(tr("Character"), w_.character);
  form->addRow(tr("Trigger"), w_.trigger);
  // A letter of the library to trace: its strokes numbered and arrowed on the paper.
  w_.guide = new QComboBox;
  w_.guide->setObjectName("record_guide");
  w_.guide->addItem(tr("none"), QString());
  addGlyphItems(w_.guide);
  w_.guide->setToolTip(tr("A letter of hattr's print script drawn on the paper to trace: each stroke numbered in "
                          "writing order, its direction arrowed"));
  connect(w_.guide, &QComboBox::activated, this,
          [this](int index) { (void)setLetterGuide(w_.guide->itemData(index).toString()); });
  form->addRow(tr("Letter guide"), w_.guide);
  layout->addLayout(form);

  // The take's buttons.
  w_.record = new QPushButton(tr("Record (R)"));
  connect(w_.record, &QPushButton::clicked, this, &RecordTab::toggle);
  w_.replay = new QPushButton(tr("Review take (P)"));
  connect(w_.replay, &QPushButton::clicked, this, [this] {
    if (take_) host_.play(*take_);
  });
  w_.retake = new QPushButton(tr("Re-take"));
  connect(w_.retake, &QPushButton::clicked, this, [this] {
    if (take_ && !take_saved_ && !host_.confirm(tr("The current take is not saved. Discard it and record again?"))) {
      return;
    }
    forgetTake();
    start();
  });
  w_.save = new QPushButton(tr("Save take… (Ctrl+S)"));
  connect(w_.save, &QPushButton::clicked, this, &RecordTab::askSave);
  w_.use = new QPushButton(tr("Use as the reference (Train)"));
  w_.use->setToolTip(tr("Train against this take without saving it first"));
  connect(w_.use, &QPushButton::clicked, this, [this] { (void)useAsReference(); });
  for (auto* b : {w_.record, w_.replay, w_.retake, w_.save, w_.use}) layout->addWidget(b);
  w_.take = wrappedLabel(tr("No take yet."));
  layout->addWidget(w_.take);
  layout->addStretch(1);
}

// ---- Actions ------------------------------------------------------------------------------

bool RecordTab::start() {
  if (!host_.idle()) return false;
  if (take_ && !take_saved_ && !host_.confirm(tr("The current take is not saved. Discard it and record a new one?"))) {
    return false;
  }
  RunSpec spec;
  spec.record = w_.trigger->currentIndex() == 0 ? RecordMode::kPenDown : RecordMode::kCommand;
  spec.metadata.subject = w_.expert->text().trimmed().toStdString();
  spec.metadata.skill = w_.character->text().trimmed().toStdString();
  spec.metadata.source = "recorded";
  try {
    host_.begin(spec);
  } catch (const std::exception& e) {
    host_.error(tr("The recording could not start"), what(e));
    return false;
  }
  armed_ = false;  // the Record/Stop trigger arms once the pen has settled
  forgetTake();
  w_.take->setText(tr("Recording…"));
  host_.changed();
  return true;
}

bool RecordTab::stop() {
  if (!host_.recording()) return false;
  // The person ends the take (its end_reason "stopped"), unless the pen-up trigger already did.
  if (!rig_.status().pen_down_done) rig_.requestStop();
  rig_.disarmRecording();
  session::TrialResult result = host_.end();
  if (result.profile.empty()) {
    w_.take->setText(tr("Nothing was recorded (the pen never touched the paper)."));
    host_.changed();
    return false;
  }
  take_ = std::move(result.profile);  // start() forgot the previous take
  take_saved_ = false;
  host_.show(*take_);
  w_.take->setText(tr("Take: %1; %2 missed samples. Not saved yet.")
                       .arg(describeProfile(*take_))
                       .arg(qs(take_->metadata().extra["missed_samples"])));
  host_.changed();
  return true;
}

void RecordTab::toggle() {
  if (host_.recording()) {
    stop();
  } else {
    start();
  }
}

bool RecordTab::save(const QString& file) {
  if (!take_) return false;
  try {
    // The take is renamed as the person typed it; the take in memory stays as it is.
    HapticProfile named = nameTake(*take_, w_.expert->text().toStdString(), w_.character->text().toStdString());
    bool saved = false;
    if (!host_.save(named, file, saved)) return false;
    take_saved_ = true;
    take_file_ = file;
    w_.take->setText(tr("Take: %1. Saved as %2.").arg(describeProfile(*take_), file.toHtmlEscaped()));
    host_.take_changed();  // a reference made of the take is now that file
    return true;
  } catch (const std::exception& e) {
    host_.error(tr("The take was not saved (it is still here)"), what(e));
    return false;
  }
}

void RecordTab::askSave() {
  if (!take_) return;
  const QString file = host_.ask_save_file(
      tr("Save the take as a haptic profile"),
      qs(suggestedTakeFileName(w_.expert->text().toStdString(), w_.character->text().toStdString())));
  if (!file.isEmpty()) save(file);
}

bool RecordTab::useAsReference() {
  if (!take_) {
    host_.error(tr("No take to use"), tr("record a take first (Record tab)"));
    return false;
  }
  return host_.use_as_reference(*take_);
}

void RecordTab::aborted() { w_.take->setText(tr("Recording aborted; nothing kept.")); }

void RecordTab::forgetTake() {
  take_.reset();
  take_saved_ = true;
  take_file_.clear();
  host_.take_changed();  // a reference made of it stays, as a take nobody can save now
}

// ---- While recording ------------------------------------------------------------------------

QString RecordTab::recordingBanner() {
  const RigStatus status = rig_.status();
  QString banner;
  if (rig_.spec().record == RecordMode::kPenDown) {
    banner = status.recording ? tr("Recording… lift the pen for 1 s to stop")
                              : (status.settling ? tr("Get ready…") : tr("Put the pen down to start recording"));
  } else if (status.settling) {
    banner = tr("Get ready…");
  } else {
    if (!armed_) rig_.armRecording();
    armed_ = true;
    banner = tr("Recording… press R to stop");
  }
  if (status.pen_down_done) stop();
  return banner;
}

void RecordTab::refresh() {
  const bool idle = host_.idle();
  const bool recording = host_.recording();
  w_.record->setText(recording ? tr("Stop recording (R)") : tr("Record (R)"));
  w_.record->setEnabled(idle || recording);
  w_.replay->setEnabled(take_.has_value() && idle);
  w_.retake->setEnabled(take_.has_value() && idle);
  w_.save->setEnabled(take_.has_value());
  w_.use->setEnabled(take_.has_value() && idle);
}

bool RecordTab::mayClose() {
  return !take_ || take_saved_ || host_.confirm(tr("The take is not saved. Quit and lose it?"));
}

void RecordTab::saveSettings() {
  settings_.setValue("record/name", w_.expert->text());
  settings_.setValue("record/character", w_.character->text());
  settings_.setValue("record/trigger", w_.trigger->currentIndex());
}

QString RecordTab::expertName() const {
  const QString name = w_.expert->text().trimmed();
  return name.isEmpty() ? tr("unnamed") : name;
}

bool RecordTab::setLetterGuide(const QString& glyph_name) {
  std::vector<std::vector<Eigen::Vector2d>> strokes;
  if (!glyph_name.isEmpty()) {
    try {
      for (const auto& stroke : sim::findBuiltInGlyph(glyph_name.toStdString()).strokes) {
        strokes.emplace_back(stroke.points.begin(), stroke.points.end());
      }
    } catch (const Error& e) {
      host_.error(tr("No such letter"), what(e));
      return false;
    }
  }
  // The character field follows the guide unless the expert typed another name.
  const QString typed = w_.character->text().trimmed();
  if (typed.isEmpty() || typed == guide_name_) w_.character->setText(glyph_name);
  guide_name_ = glyph_name;
  guide_m_ = std::move(strokes);
  w_.guide->setCurrentIndex(std::max(0, w_.guide->findData(glyph_name)));
  settings_.setValue("record/guide", glyph_name);
  host_.show_guide(guide_m_);
  return true;
}

QString RecordTab::character() const {
  const QString character = w_.character->text().trimmed();
  return character.isEmpty() ? tr("no character") : character;
}

}  // namespace hattr::studio
