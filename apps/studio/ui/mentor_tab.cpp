#include "ui/mentor_tab.hpp"

#include <QCheckBox>
#include <QComboBox>
#include <QDateTime>
#include <QDoubleSpinBox>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>
#include <algorithm>

#include "hattr/session/trial.hpp"
#include "ui/paper_view.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {
namespace {

constexpr int kStatusPeriod_ms = 250;
constexpr net::Coupling kCouplings[] = {net::Coupling::kObserve, net::Coupling::kPosition, net::Coupling::kForce,
                                        net::Coupling::kBilateral};

/// The other station's pen as the paper view draws a pen.
Sample peerSample(const net::PeerView& peer) {
  Sample s;
  s.t_s = peer.t_s;
  s.p_WT = peer.p_WT;
  s.v_WT = peer.v_WT;
  s.f_user_W = peer.f_user_W;
  s.pen_down = peer.pen_down;
  s.in_contact = peer.pen_down;
  return s;
}

/// The drops that happened, by reason ("bad MAC 2, busy 1"), or "none".
QString dropsText(const net::MentorStats& stats) {
  QStringList parts;
  for (std::size_t i = 0; i < stats.drops.size(); ++i) {
    if (stats.drops[i] == 0) continue;
    parts << QStringLiteral("%1 %2")
                 .arg(qs(wire::dropReasonName(static_cast<wire::DropReason>(i))))
                 .arg(stats.drops[i]);
  }
  return parts.isEmpty() ? QObject::tr("none") : parts.join(QStringLiteral(", "));
}

}  // namespace

MentorTab::MentorTab(MouseHand& hand, PaperView& paper, QSettings& settings, MentorHost host, QWidget* parent)
    : QWidget(parent), hand_(hand), paper_(paper), settings_(settings), host_(std::move(host)) {
  buildUi();
  loadSettings();
  status_clock_.start();
  refresh();
}

MentorTab::~MentorTab() = default;

// ---- Construction ------------------------------------------------------------------------

void MentorTab::buildUi() {
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(wrappedLabel(
      tr("<b>Mentor</b> live over the network: the expert <b>leads</b> (listens), the trainee "
         "<b>follows</b> (connects to the expert's address and picks the coupling). Each sees the other's pen "
         "live on the paper; both use the same key file (<tt>hattr device keygen --out mentor.key</tt>). "
         "Your pen is the studio's device, held by the mouse or tablet.")));

  // What the person chooses.
  buildChoices(layout);

  // Start, stop, save.
  buildControls(layout);
}

// What the person chooses: role, address, coupling, key file, passivity, deadband, wait.
void MentorTab::buildChoices(QVBoxLayout* layout) {
  auto* form = new QFormLayout;
  w_.role = new QComboBox;
  w_.role->addItem(tr("Lead (expert: listen)"));
  w_.role->addItem(tr("Follow (trainee: connect)"));
  w_.address = new QLineEdit;
  w_.coupling = new QComboBox;
  for (const net::Coupling c : kCouplings) w_.coupling->addItem(qs(net::couplingName(c)));
  w_.coupling->setToolTip(
      tr("observe: no force, the pens are shown · position: you are pulled toward the expert's pen · force: you "
         "feel the difference between the expert's force on the paper and yours · bilateral: a spring between the "
         "two pens acts on both"));
  auto* key_row = new QHBoxLayout;
  w_.key_file = new QLineEdit;
  w_.key_file->setPlaceholderText(tr("mentor.key (hattr device keygen)"));
  auto* browse = new QPushButton(tr("Browse…"));
  connect(browse, &QPushButton::clicked, this, [this] {
    const QString file = host_.ask_open_file(tr("Choose the shared key file"), tr("Key files (*.key);;All files (*)"));
    if (!file.isEmpty()) w_.key_file->setText(file);
  });
  key_row->addWidget(w_.key_file, 1);
  key_row->addWidget(browse);
  w_.passivity = new QCheckBox(tr("Passivity controller"));
  w_.passivity->setChecked(true);
  w_.passivity->setToolTip(tr("The time-domain passivity observer and controller: keeps the bilateral coupling "
                              "stable under network delay (docs/mentoring.md). Off only for experiments."));
  w_.deadband = new QDoubleSpinBox;
  w_.deadband->setRange(0.0, 1.0);
  w_.deadband->setSingleStep(0.05);
  w_.deadband->setDecimals(2);
  w_.deadband->setSpecialValueText(tr("off (a packet every tick)"));
  w_.deadband->setToolTip(tr("Perceptual deadband: send a packet only when velocity or force changed by more than this "
                             "fraction (0.1 is typical; off: every millisecond)"));
  w_.wait = new QDoubleSpinBox;
  w_.wait->setRange(1.0, 3600.0);
  w_.wait->setValue(30.0);
  w_.wait->setSuffix(tr(" s"));
  w_.wait->setToolTip(tr("Give up when the other station has not answered within this time"));
  form->addRow(tr("Role"), w_.role);
  form->addRow(tr("Address"), w_.address);
  form->addRow(tr("Coupling"), w_.coupling);
  form->addRow(tr("Key file"), key_row);
  form->addRow(QString(), w_.passivity);
  form->addRow(tr("Deadband"), w_.deadband);
  form->addRow(tr("Wait"), w_.wait);
  layout->addLayout(form);
  form_ = form;
  connect(w_.role, &QComboBox::activated, this, [this] { onRoleChanged(); });
}

// Start, stop, save: the buttons and the labels that show the session.
void MentorTab::buildControls(QVBoxLayout* layout) {
  auto* row = new QHBoxLayout;
  w_.connect = new QPushButton;
  connect(w_.connect, &QPushButton::clicked, this, [this] { (void)connectSession(); });
  w_.disconnect = new QPushButton(tr("Disconnect"));
  connect(w_.disconnect, &QPushButton::clicked, this, [this] { (void)disconnectSession(); });
  row->addWidget(w_.connect, 1);
  row->addWidget(w_.disconnect, 1);
  layout->addLayout(row);
  w_.phase = wrappedLabel();
  QFont big = w_.phase->font();
  big.setPointSizeF(big.pointSizeF() * 1.2);
  big.setBold(true);
  w_.phase->setFont(big);
  layout->addWidget(w_.phase);
  w_.status = wrappedLabel();
  layout->addWidget(w_.status);
  w_.clamps = wrappedLabel();
  layout->addWidget(w_.clamps);
  w_.save = new QPushButton(tr("Save recording…"));
  connect(w_.save, &QPushButton::clicked, this, [this] {
    const QString suggested =
        QStringLiteral("mentored_%1_%2.csv")
            .arg(role() == net::MentorRole::kLeader ? QStringLiteral("expert") : QStringLiteral("trainee"),
                 QDateTime::currentDateTime().toString(QStringLiteral("yyyyMMdd-HHmmss")));
    const QString file = host_.ask_save_file(tr("Save this station's recording as a haptic profile"), suggested);
    if (!file.isEmpty()) (void)saveRecording(file);
  });
  layout->addWidget(w_.save);
  w_.recording = wrappedLabel(tr("No recording yet."));
  layout->addWidget(w_.recording);
  layout->addStretch(1);
}

void MentorTab::loadSettings() {
  const int role_index = std::clamp(settings_.value("mentor/role", 0).toInt(), 0, 1);
  listen_address_ = settings_.value("mentor/listen", QString::fromLatin1(kDefaultListenAddress)).toString();
  connect_address_ = settings_.value("mentor/connect").toString();
  w_.role->setCurrentIndex(role_index);
  shown_role_ = -1;
  w_.coupling->setCurrentIndex(std::clamp(settings_.value("mentor/coupling", 0).toInt(), 0, 3));
  w_.key_file->setText(settings_.value("mentor/key_file").toString());
  w_.passivity->setChecked(settings_.value("mentor/passivity", true).toBool());
  w_.deadband->setValue(settings_.value("mentor/deadband", 0.0).toDouble());
  w_.wait->setValue(settings_.value("mentor/wait_s", 30.0).toDouble());
  onRoleChanged();
}

void MentorTab::saveSettings() {
  (role() == net::MentorRole::kLeader ? listen_address_ : connect_address_) = w_.address->text().trimmed();
  settings_.setValue("mentor/role", w_.role->currentIndex());
  settings_.setValue("mentor/listen", listen_address_);
  settings_.setValue("mentor/connect", connect_address_);
  settings_.setValue("mentor/coupling", w_.coupling->currentIndex());
  settings_.setValue("mentor/key_file", w_.key_file->text().trimmed());
  settings_.setValue("mentor/passivity", w_.passivity->isChecked());
  settings_.setValue("mentor/deadband", w_.deadband->value());
  settings_.setValue("mentor/wait_s", w_.wait->value());
}

// Each role keeps its own address; only the follower picks the coupling.
void MentorTab::onRoleChanged() {
  const bool lead = role() == net::MentorRole::kLeader;
  if (shown_role_ >= 0) (shown_role_ == 0 ? listen_address_ : connect_address_) = w_.address->text().trimmed();
  shown_role_ = w_.role->currentIndex();
  w_.address->setText(lead ? listen_address_ : connect_address_);
  w_.address->setPlaceholderText(lead ? tr("ADDR:PORT to listen on, e.g. 0.0.0.0:7400")
                                      : tr("the expert's HOST:PORT, e.g. 192.168.1.20:7400"));
  w_.connect->setText(lead ? tr("Listen") : tr("Connect"));
  refresh();
}

// ---- Actions -------------------------------------------------------------------------------

net::MentorRole MentorTab::role() const {
  return w_.role->currentIndex() == 0 ? net::MentorRole::kLeader : net::MentorRole::kFollower;
}

MentorSettings MentorTab::settingsFromWidgets() const {
  MentorSettings s;
  s.role = role();
  s.address = w_.address->text().trimmed().toStdString();
  s.key_file = w_.key_file->text().trimmed().toStdString();
  s.coupling = kCouplings[std::clamp(w_.coupling->currentIndex(), 0, 3)];
  s.passivity = w_.passivity->isChecked();
  s.deadband = w_.deadband->value();
  s.wait_s = w_.wait->value();
  return s;
}

bool MentorTab::connectSession() {
  if (session_.active()) return false;
  if (!confirmDiscard(tr("The last mentored recording is not saved. Discard it and start a new session?"))) {
    return false;
  }
  MentorSettings settings = settingsFromWidgets();
  const QString failed = tr("The mentoring session could not start");
  // The key and the address are checked before the window's device is taken.
  try {
    (void)mentorSetupFor(settings);
  } catch (const std::exception& e) {
    w_.phase->setText(tr("Not started: %1").arg(QString::fromUtf8(e.what())));
    host_.error(failed, QString::fromUtf8(e.what()));
    return false;
  }
  QString why;
  const session::TrialEnvironment* environment = host_.claim(why);
  if (environment == nullptr) {
    w_.phase->setText(tr("Not started: %1").arg(why));
    host_.error(failed, why);
    return false;
  }
  settings.device_uri = environment->deviceUri();
  settings.world = environment->world();
  settings.rate_hz = environment->rate_hz();
  try {
    session_.start(settings, hand_);
  } catch (const std::exception& e) {
    host_.release();
    w_.phase->setText(tr("Not started: %1").arg(QString::fromUtf8(e.what())));
    host_.error(failed, QString::fromUtf8(e.what()));
    refresh();
    return false;
  }
  saveSettings();
  paper_.trail().clear();
  paper_.setPeer(&session_.peerTrail(), std::nullopt, peerLabel());
  refresh();
  refreshStatus();
  return true;
}

bool MentorTab::disconnectSession() {
  if (!session_.active()) return false;
  session_.stop();
  sessionOver();
  return true;
}

void MentorTab::toggleSession() {
  if (session_.active()) {
    (void)disconnectSession();
  } else {
    (void)connectSession();
  }
}

void MentorTab::shutdown() { session_.stop(); }

void MentorTab::frame() {
  if (!session_.active()) return;
  const bool ended = session_.poll();
  if (session_.ownPenFresh()) paper_.trail().append(*session_.ownPen());
  paper_.setPen(session_.ownPen());
  const net::PeerView& peer = session_.peer();
  paper_.setPeer(&session_.peerTrail(), peer.valid ? std::optional<Sample>(peerSample(peer)) : std::nullopt,
                 peerLabel());
  paper_.setBanner(banner(session_.snapshot()));
  if (ended) {
    sessionOver();
  } else if (status_clock_.elapsed() >= kStatusPeriod_ms) {
    refreshStatus();
  }
}

// The session ended (the person, or by itself): the device goes back, the recording stays.
void MentorTab::sessionOver() {
  paper_.setPeer(&session_.peerTrail(), std::nullopt, peerLabel());
  paper_.setBanner({});
  host_.release();
  refresh();
  refreshStatus();
  const MentorSnapshot s = session_.snapshot();
  if (!s.failure.empty()) {
    host_.error(tr("The mentoring session ended"),
                qs(s.failure) + (session_.recording() ? tr("\n\nWhat was recorded is kept (marked failed): save it "
                                                           "with Save recording…")
                                                      : QString()));
  }
}

bool MentorTab::saveRecording(const QString& file) {
  if (!session_.recording()) return false;
  try {
    SaveOutcome outcome = session_.saveRecording(file.toStdString(), false);
    if (outcome == SaveOutcome::kNeedsConfirmation) {
      if (!host_.confirm(tr("%1 already exists. Replace it?").arg(file))) {
        w_.recording->setText(w_.recording->text() + tr("<br>%1 exists: not replaced.").arg(file.toHtmlEscaped()));
        return false;
      }
      outcome = session_.saveRecording(file.toStdString(), true);
    }
    if (outcome != SaveOutcome::kSaved) return false;
    w_.recording->setText(w_.recording->text() + tr("<br>Saved as %1.").arg(file.toHtmlEscaped()));
    return true;
  } catch (const std::exception& e) {
    host_.error(tr("Not saved (nothing is lost: it is still in memory)"), QString::fromUtf8(e.what()));
    return false;
  }
}

bool MentorTab::confirmDiscard(const QString& question) {
  if (!session_.recording() || session_.recordingSaved()) return true;
  if (!host_.confirm(question)) return false;
  session_.discardRecording();
  return true;
}

bool MentorTab::mayClose() {
  if (session_.active()) (void)disconnectSession();  // what was recorded so far is kept for the question
  return confirmDiscard(tr("The mentored recording is not saved. Quit and lose it?"));
}

void MentorTab::clearPeerTrail() { session_.clearPeerTrail(); }

void MentorTab::setRole(net::MentorRole r) {
  if (session_.active()) return;
  w_.role->setCurrentIndex(r == net::MentorRole::kLeader ? 0 : 1);
  onRoleChanged();
}

void MentorTab::setEngineerView(bool on) {
  engineer_view_ = on;
  form_->setRowVisible(w_.passivity, on);
  form_->setRowVisible(w_.deadband, on);
  refreshStatus();
}

// ---- Display -------------------------------------------------------------------------------

QString MentorTab::peerLabel() const {
  return role() == net::MentorRole::kLeader ? tr("trainee") : tr("expert");
}

QString MentorTab::banner(const MentorSnapshot& snapshot) const {
  switch (snapshot.phase) {
    case MentorPhase::kWaiting: return qs(snapshot.where) + QStringLiteral("…");
    case MentorPhase::kLinked:
      if (snapshot.link_down_now) return tr("Link down: no coupling force");
      return snapshot.linked_s < 1.5 ? tr("Linked: you see the %1's pen").arg(peerLabel()) : QString();
    case MentorPhase::kIdle:
    case MentorPhase::kEnded: return {};
  }
  return {};
}

void MentorTab::refresh() {
  const bool active = session_.active();
  for (QWidget* w : std::initializer_list<QWidget*>{w_.role, w_.address, w_.key_file, w_.passivity, w_.deadband, w_.wait}) {
    w->setEnabled(!active);
  }
  w_.coupling->setEnabled(!active && role() == net::MentorRole::kFollower);
  w_.connect->setEnabled(!active);
  w_.disconnect->setEnabled(active);
  w_.save->setEnabled(!active && session_.recording().has_value());
}

// The link, the packets, the energies, the loop, the clamps, the recording.
void MentorTab::refreshStatus() {
  status_clock_.restart();
  const MentorSnapshot s = session_.snapshot();
  QString phase = qs(mentorPhaseText(s));
  if (s.phase == MentorPhase::kLinked && s.role == net::MentorRole::kFollower && !s.link_down_now) {
    phase += tr(": coupling %1").arg(w_.coupling->currentText());
  }
  if (s.phase == MentorPhase::kEnded && !s.failure.empty()) {
    w_.phase->setStyleSheet(QStringLiteral("color: #b00020"));
  } else {
    w_.phase->setStyleSheet({});
  }
  w_.phase->setText(phase);
  w_.disconnect->setText(s.phase == MentorPhase::kWaiting && s.role == net::MentorRole::kLeader ? tr("Stop listening")
                                                                                               : tr("Disconnect"));
  if (s.phase == MentorPhase::kIdle) {
    w_.status->clear();
  } else if (!engineer_view_) {
    w_.status->setText(tr("<b>Link</b> %1 · round trip %2 ms")
                           .arg(s.stats.link_up ? tr("up") : tr("down"))
                           .arg(s.stats.rtt_s * 1e3, 0, 'f', 1));
  } else {
    const net::MentorStats& m = s.stats;
    w_.status->setText(
        tr("<b>Link</b> %1 · round trip %2 ms · link faults %3<br>"
           "<b>Packets</b> in %4 · out %5 (withheld %6) · lost %7 · dropped: %8<br>"
           "<b>Energy</b> in %9 J · out %10 J · dissipated %11 J (the other's in, as heard: %12 J)<br>"
           "<b>Loop</b> %13 ticks · overruns %14 · faults %15 · stalls %16")
            .arg(m.link_up ? tr("up") : tr("down"))
            .arg(m.rtt_s * 1e3, 0, 'f', 1)
            .arg(m.link_faults)
            .arg(m.peers_received)
            .arg(m.peers_sent)
            .arg(m.peers_withheld)
            .arg(m.lost)
            .arg(dropsText(m))
            .arg(m.energy_in_J, 0, 'f', 4)
            .arg(m.energy_out_J, 0, 'f', 4)
            .arg(m.dissipated_J, 0, 'f', 4)
            .arg(m.peer_energy_in_J, 0, 'f', 4)
            .arg(s.ticks)
            .arg(s.overruns)
            .arg(s.faults)
            .arg(s.stalls));
  }
  QString clamps;
  for (const auto& line : session_.clamps()) clamps += QStringLiteral("<br>· ") + qs(line).toHtmlEscaped();
  w_.clamps->setVisible(engineer_view_);
  w_.clamps->setText(s.phase == MentorPhase::kIdle ? QString()
                     : clamps.isEmpty()            ? tr("Clamped to the device: nothing")
                                                   : tr("Clamped to the device:%1").arg(clamps));
  // The recording of the last session.
  if (!session_.active()) {
    const auto& r = session_.recording();
    if (!r) {
      w_.recording->setText(s.phase == MentorPhase::kEnded ? tr("Nothing was recorded (the stations never linked).")
                                                           : tr("No recording yet."));
    } else if (!session_.recordingSaved()) {
      const auto failed = r->metadata().extra.find("failed");
      w_.recording->setText(tr("Recorded %1 s (%2 samples)%3. Not saved yet.")
                                .arg(r->duration_s(), 0, 'f', 2)
                                .arg(r->size())
                                .arg(failed == r->metadata().extra.end()
                                         ? QString()
                                         : tr(", marked failed (%1)").arg(qs(failed->second).toHtmlEscaped())));
    }
  } else {
    w_.recording->setText(s.phase == MentorPhase::kLinked ? tr("Recording this station's side…")
                                                          : tr("Recording starts once linked."));
  }
}

}  // namespace hattr::studio
