#include "ui/train_tab.hpp"

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileInfo>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/profile_files.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/strategy_schedule.hpp"
#include "hattr/library/profile_template.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "ui/learning_curve.hpp"
#include "ui/library_dialog.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

TrainTab::TrainTab(QSettings& settings, TrainHost host, QWidget* parent)
    : QWidget(parent), settings_(settings), host_(std::move(host)) {
  buildUi();
  w_.indexing->setCurrentIndex(settings_.value("train/indexing", 0).toInt());
  w_.show_reference->setChecked(settings_.value("train/show_reference", true).toBool());
  w_.settle->setValue(settings_.value("train/settle_s", 1.5).toDouble());
  // A remembered strategy the tab offers, else BASIC.
  const int remembered = w_.mode->findData(settings_.value("train/mode", 0).toInt());
  mode_ = static_cast<guidance::TrainingMode>(w_.mode->itemData(std::max(remembered, 0)).toInt());
  w_.mode->setCurrentIndex(std::max(remembered, 0));
}

TrainTab::~TrainTab() = default;

// ---- Construction ------------------------------------------------------------------------

void TrainTab::buildUi() {
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(
      wrappedLabel(tr("<b>Train</b> against a reference: an expert's haptic profile or a letter. After each "
                      "trial two scores compare your writing with it, its shape and its force; lower is closer.")));
  buildReferenceChoice(*layout);

  // The mode, its indexing, the get-ready time and whether the reference is drawn.
  auto* form = new QFormLayout;
  // Every strategy but the mentored ones (the Mentor tab's): its plain name, the technical
  // name beside, what it does in the tooltip.
  w_.mode = new QComboBox;
  for (const auto& strategy : guidance::strategyCatalog()) {
    if (strategy.mentored) continue;
    w_.mode->addItem(qs(strategy.plain_name), static_cast<int>(strategy.mode));  // setEngineerView names it
    w_.mode->setItemData(w_.mode->count() - 1,
                         qs(guidance::modeName(strategy.mode)) + QStringLiteral(": ") + qs(strategy.description),
                         Qt::ToolTipRole);
  }
  // The longest names are shown elided: the tab keeps its width on a small screen.
  w_.mode->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
  w_.mode->setMinimumContentsLength(22);
  w_.mode->setToolTip(tr("The training strategy (`hattr strategies`); keys 1, 2, 3: the paper's BASIC, PCONTROL, "
                         "ALPHA"));
  connect(w_.mode, &QComboBox::activated, this,
          [this](int index) { setMode(static_cast<guidance::TrainingMode>(w_.mode->itemData(index).toInt())); });
  w_.indexing = new QComboBox;
  w_.indexing->addItem(tr("time (the paper's)"));
  w_.indexing->addItem(tr("progress (follows you)"));
  w_.show_reference = new QCheckBox(tr("Show the reference"));
  w_.show_reference->setChecked(true);
  connect(w_.show_reference, &QCheckBox::toggled, this, [this](bool on) { host_.reference_shown(on); });
  w_.settle = new QDoubleSpinBox;
  w_.settle->setRange(0.3, 10.0);
  w_.settle->setSingleStep(0.5);
  w_.settle->setSuffix(tr(" s"));
  w_.settle->setValue(1.5);
  w_.settle->setToolTip(
      tr("Before each trial the pen is held lifted this long while the forces ramp in; move "
         "to the start meanwhile"));
  form->addRow(tr("Mode"), w_.mode);
  form->addRow(tr("Indexing"), w_.indexing);
  form->addRow(tr("Get ready"), w_.settle);
  form->addRow(QString(), w_.show_reference);
  layout->addLayout(form);

  // The trial's buttons, its scores and the learning curve.
  w_.trial = new QPushButton(tr("Start trial (Space)"));
  connect(w_.trial, &QPushButton::clicked, this, [this] {
    if (host_.trial_running()) {
      host_.stop_trial();
    } else {
      start();
    }
  });
  w_.replay = new QPushButton(tr("Replay trial (P)"));
  connect(w_.replay, &QPushButton::clicked, this, [this] { host_.replay_last_trial(); });
  w_.save = new QPushButton(tr("Save trial… (Ctrl+Shift+S)"));
  connect(w_.save, &QPushButton::clicked, this, [this] { host_.save_last_trial(); });
  for (auto* b : {w_.trial, w_.replay, w_.save}) layout->addWidget(b);
  w_.scores = wrappedLabel();
  layout->addWidget(w_.scores);
  w_.curve = new LearningCurve;
  layout->addWidget(w_.curve);
  layout->addStretch(1);
}

// ---- The reference ------------------------------------------------------------------------

// The reference: what it is, a file to open, or a letter the simulated expert writes.
void TrainTab::buildReferenceChoice(QVBoxLayout& layout) {
  w_.reference = wrappedLabel(tr("No reference loaded."));
  layout.addWidget(w_.reference);
  auto* open = new QPushButton(tr("Open reference… (Ctrl+O)"));
  connect(open, &QPushButton::clicked, this, [this] {
    const QString file = host_.ask_open_file(tr("Open a reference profile"), tr("Haptic profiles (*.csv);;All files (*)"));
    if (!file.isEmpty()) loadReference(file);
  });
  layout.addWidget(open);
  // Or a person's template from a profile library.
  w_.library = new QPushButton(tr("From a profile library…"));
  w_.library->setToolTip(tr("Train against a person's template (the average of their genuine recordings), or find "
                            "whose writing a profile is nearest"));
  connect(w_.library, &QPushButton::clicked, this, [this] {
    const QString file =
        host_.ask_open_file(tr("Open a profile library"), tr("Profile libraries (*.sqlite *.db);;All files (*)"));
    if (!file.isEmpty()) openLibrary(file);
  });
  layout.addWidget(w_.library);
  // Or a letter of the library (or another built-in glyph), written by the simulated expert.
  w_.letter = new QComboBox;
  w_.letter->addItem(tr("Or write a letter: choose one"), QString());
  addGlyphItems(w_.letter);
  w_.letter->setToolTip(tr("The simulated expert writes the letter in hattr's print script on the simulated pen "
                           "(as hattr sim expert --glyph does), and that becomes the reference"));
  connect(w_.letter, &QComboBox::activated, this, [this](int index) {
    const QString name = w_.letter->itemData(index).toString();
    if (!name.isEmpty()) useLetter(name);
  });
  layout.addWidget(w_.letter);
}


// Whether the reference may change now; if not, the window says why.
bool TrainTab::referenceMayChange() {
  if (host_.may_change_reference()) return true;
  host_.error(tr("The reference cannot change now"), tr("finish or abort the trial first (Esc)"));
  return false;
}

bool TrainTab::loadReference(const QString& file) {
  if (!referenceMayChange()) return false;
  try {
    HapticProfile profile = loadReferenceProfile(file.toStdString());
    // A template is named by its person, skill and library; a file by its name.
    const bool from_library = library::isLibraryReference(file.toStdString());
    const QString label =
        from_library
            ? tr("Reference: the template of <b>%1</b>'s %2 in %3, the %4: %5")
                  .arg(qs(profile.metadata().subject).toHtmlEscaped(), qs(profile.metadata().skill).toHtmlEscaped(),
                       QFileInfo(file.mid(8, file.lastIndexOf('#') - 8)).fileName().toHtmlEscaped(),
                       qs(profile.metadata().source).toHtmlEscaped(), describeProfile(profile))
            : tr("Reference <b>%1</b> (%2, %3): %4")
                  .arg(QFileInfo(file).fileName().toHtmlEscaped(), qs(profile.metadata().subject).toHtmlEscaped(),
                       qs(profile.metadata().skill).toHtmlEscaped(), describeProfile(profile));
    setReference(std::move(profile), file, from_library ? file : QFileInfo(file).fileName(), label);
    return true;
  } catch (const std::exception& e) {
    host_.error(tr("The reference could not be loaded"), what(e));
    return false;
  }
}

bool TrainTab::openLibrary(const QString& location) {
  if (!referenceMayChange()) return false;
  std::unique_ptr<LibraryDialog> dialog;
  try {
    dialog = std::make_unique<LibraryDialog>(location, host_.last_trial(), host_.ask_open_file, this);
  } catch (const std::exception& e) {
    host_.error(tr("The profile library could not be opened"), what(e));
    return false;
  }
  if (dialog->exec() != QDialog::Accepted || dialog->reference().isEmpty()) return false;
  return loadReference(dialog->reference());
}

bool TrainTab::useLetter(const QString& glyph_name) {
  if (!referenceMayChange()) return false;
  try {
    const sim::Glyph glyph = sim::findBuiltInGlyph(glyph_name.toStdString());
    // The simulated expert on the simulated pen and the default paper, at the studio's rate.
    session::TrialEnvironment pen("sim://pen", render::WorldConfig{}, host_.rate_hz());
    HapticProfile profile =
        sim::recordExpert(pen, sim::expertScript(glyph), {.subject = "expert", .skill = glyph.name, .source = "sim:expert"});
    // A character is "the letter a (small-a)"; a shape that is none, "the glyph loop".
    const QString label =
        glyph.character.empty()
            ? tr("Reference: the glyph <b>%1</b> written by the simulated expert: %2")
                  .arg(qs(glyph.name).toHtmlEscaped(), describeProfile(profile))
            : tr("Reference: the letter <b>%1</b> (%2) written by the simulated expert: %3")
                  .arg(qs(glyph.character).toHtmlEscaped(), qs(glyph.name).toHtmlEscaped(), describeProfile(profile));
    // Named "glyph:NAME" in the trials' metadata, so that it is not taken for a file's name.
    setReference(std::move(profile), QString(), QStringLiteral("glyph:%1").arg(qs(glyph.name)), label);
    reference_letter_ = qs(glyph.name);
    w_.letter->setCurrentIndex(std::max(0, w_.letter->findData(reference_letter_)));
    return true;
  } catch (const std::exception& e) {
    host_.error(tr("The letter could not be written"), what(e));
    return false;
  }
}

bool TrainTab::useTake(const HapticProfile& take, const TakeName& name) {
  if (!host_.idle()) {
    host_.error(tr("The reference cannot change now"), tr("finish the trial, recording or session first"));
    return false;
  }
  try {
    checkReferenceProfile(take, "the take");
  } catch (const std::exception& e) {
    host_.error(tr("The take cannot be the reference"), what(e));
    return false;
  }
  setReference(take, QString(), QString(), QString());
  reference_is_take_ = true;
  nameTake(name);
  return true;
}

void TrainTab::takeRenamed(const TakeName& name) {
  if (reference_is_take_) nameTake(name);
}

// The take as the reference is named by the file it was saved to, if it was; else "take (not saved)".
void TrainTab::nameTake(const TakeName& name) {
  const bool saved = !name.file.isEmpty();
  reference_file_ = name.file;
  reference_name_ = saved ? QFileInfo(name.file).fileName() : QStringLiteral("take (not saved)");
  w_.reference->setText(tr("Reference: <b>the take</b> (%1, %2, %3): %4")
                            .arg(name.expert.toHtmlEscaped(), name.character.toHtmlEscaped(),
                                 saved ? tr("saved as %1").arg(name.file.toHtmlEscaped()) : tr("not saved"),
                                 describeProfile(*reference_)));
}

void TrainTab::setReference(HapticProfile profile, const QString& file, const QString& name,
                            const QString& label_html) {
  reference_ = std::move(profile);
  reference_file_ = file;
  reference_name_ = name;
  reference_is_take_ = false;
  reference_letter_.clear();
  w_.letter->setCurrentIndex(0);
  w_.reference->setText(label_html);
  w_.curve->clear();  // scores against another reference do not compare
  scheduled_errors_.clear();  // nor do its tracking errors
  host_.show_reference(*reference_, referenceShown());
  host_.changed();
}

// ---- The mode and the trial -----------------------------------------------------------------

void TrainTab::setMode(guidance::TrainingMode mode) {
  // A scheduled strategy's law and gain are chosen before its trial: not switched into or out of.
  if (host_.trial_running() && mode != trial_mode_ &&
      (guidance::isScheduled(mode) || guidance::isScheduled(trial_mode_))) {
    w_.mode->setCurrentIndex(w_.mode->findData(static_cast<int>(mode_)));
    host_.error(tr("The strategy cannot change during this trial"),
                tr("%1 sets its guidance before each trial from the trials before it; choose it between trials")
                    .arg(qs(guidance::strategyInfo(guidance::isScheduled(mode) ? mode : trial_mode_).plain_name)));
    return;
  }
  mode_ = mode;
  w_.mode->setCurrentIndex(w_.mode->findData(static_cast<int>(mode)));
  // During a trial the mode switches through the servo mailbox, with the cross-fade.
  if (host_.trial_running() && !host_.switch_mode(mode)) {
    host_.error(tr("The mode could not be switched"), tr("the servo loop's mailbox is full; try again"));
  }
}

bool TrainTab::start() {
  if (!host_.idle()) return false;
  if (!reference_) {
    host_.error(tr("No reference"), tr("open an expert's haptic profile first (Ctrl+O)"));
    return false;
  }
  try {
    auto reference = std::make_shared<guidance::ReferenceTrajectory>(*reference_, host_.rate_hz());
    session::TrialSetup setup;
    setup.guidance.mode = mode_;
    // A scheduled strategy's law and gain from this reference's trials in it so far.
    setup.guidance.scheduled = guidance::scheduleTrial(setup.guidance, mode_, scheduled_errors_[mode_]);
    setup.guidance.playback.indexing =
        w_.indexing->currentIndex() == 0 ? guidance::Indexing::kTime : guidance::Indexing::kProgress;
    // A study's default end: 1 s with the pen lifted after writing, at most 3 × the expert.
    const session::TrialEndRule end = session::Protocol{}.trial_end;
    setup.duration_s = end.maxDuration_s(reference->duration_s());
    setup.pen_up_end_s = end.pen_up_s;
    setup.reference = std::move(reference);
    setup.settle_s = settle_s();
    setup.clock = session::Clock::kRealTime;
    setup.metadata.subject = "trainee";
    setup.metadata.skill = reference_->metadata().skill;
    setup.metadata.source = "studio";
    setup.metadata.extra["reference_file"] = reference_name_.toStdString();
    QString title = tr("Trial: %1").arg(qs(guidance::strategyInfo(mode_).plain_name));
    if (guidance::isScheduled(mode_)) {
      const guidance::TrainingMode law = setup.guidance.scheduled.law;
      title += tr(" (%1 at %2 %)")
                   .arg(engineer_view_ ? qs(guidance::modeName(law)) : qs(guidance::strategyInfo(law).plain_name))
                   .arg(std::round(100.0 * setup.guidance.scheduled.gain));
    }
    host_.start_trial(setup, *reference_, referenceShown(), title, w_.scores);
  } catch (const std::exception& e) {
    host_.error(tr("The trial could not start"), what(e));
    return false;
  }
  trial_mode_ = mode_;
  return true;
}

void TrainTab::trialEnded(const std::optional<analysis::TrialScore>& scores, const session::TrialResult& result) {
  // A trial the device or the loop cut short (failure) is scored, but is no point of the curve,
  // nor one a scheduled strategy learns from.
  if (scores && result.failure.empty()) w_.curve->add(trial_mode_, *scores);
  if (guidance::isScheduled(trial_mode_) && result.failure.empty() && !result.profile.empty() && reference_) {
    const guidance::ReferenceTrajectory expert(*reference_, host_.rate_hz());
    scheduled_errors_[trial_mode_].push_back(guidance::trackingErrorRms(expert, result.profile));
  }
  if (!engineer_view_) return;
  w_.scores->setText(w_.scores->text() + tr("<br>%1 ticks, %2 overruns, %3 missed samples, %4 faults")
                                             .arg(result.ticks)
                                             .arg(result.overruns)
                                             .arg(result.missed_samples)
                                             .arg(result.faults));
}

void TrainTab::setEngineerView(bool on) {
  engineer_view_ = on;
  for (int i = 0; i < w_.mode->count(); ++i) {
    const auto& info = guidance::strategyInfo(static_cast<guidance::TrainingMode>(w_.mode->itemData(i).toInt()));
    w_.mode->setItemText(i, on ? tr("%1 — %2").arg(qs(info.plain_name), qs(guidance::modeName(info.mode)))
                               : qs(info.plain_name));
  }
}

void TrainTab::aborted() { w_.scores->setText(tr("Trial aborted; nothing kept.")); }

// ---- Buttons and settings -------------------------------------------------------------------

void TrainTab::refresh() {
  const bool idle = host_.idle();
  const bool running = host_.trial_running();
  w_.trial->setText(running ? tr("Stop trial (Space, Ctrl+.)") : tr("Start trial (Space)"));
  w_.trial->setEnabled((idle && reference_) || running);
  w_.replay->setEnabled(host_.has_last_trial() && idle);
  w_.save->setEnabled(host_.has_last_trial());
}

void TrainTab::saveSettings() {
  settings_.setValue("train/mode", static_cast<int>(mode_));
  settings_.setValue("train/indexing", w_.indexing->currentIndex());
  settings_.setValue("train/show_reference", w_.show_reference->isChecked());
  settings_.setValue("train/settle_s", w_.settle->value());
  // An unsaved take as the reference is not remembered; the last file or letter stays.
  if (!reference_file_.isEmpty()) {
    settings_.setValue("train/reference_file", reference_file_);
    settings_.remove("train/reference_letter");
  } else if (!reference_letter_.isEmpty()) {
    settings_.setValue("train/reference_letter", reference_letter_);
    settings_.remove("train/reference_file");
  }
}

bool TrainTab::referenceShown() const { return w_.show_reference->isChecked(); }

double TrainTab::settle_s() const { return w_.settle->value(); }

}  // namespace hattr::studio
