#pragma once
/// The Mentor tab: live mentoring from the studio, for either role (docs/studio.md). The expert
/// leads (listens on ADDR:PORT), the trainee follows (connects to the expert's HOST:PORT and
/// picks the coupling); both choose the shared key file. While a session runs the tab has the
/// studio's device and hand (the main window's own loop is stopped), draws this station's pen
/// as usual and the other station's pen and trail in their own colour, and shows the link, the
/// packets, the energies and the clamps. The logic is MentorSession's (core/mentor_session.hpp);
/// this file is the widgets. GUI thread only.

#include <QElapsedTimer>
#include <QString>
#include <QWidget>
#include <functional>

#include "core/mentor_session.hpp"
#include "core/mouse_hand.hpp"

class QCheckBox;
class QComboBox;
class QFormLayout;
class QDoubleSpinBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QSettings;
class QVBoxLayout;

namespace hattr::session {
class TrialEnvironment;
}

namespace hattr::studio {

class PaperView;

/// What the main window lends the tab: its device and its dialogs.
struct MentorHost {
  /// Stops the window's own loop and lends the studio's current device (URI, world, rate);
  /// null, with why, when it cannot now (a trial or a recording runs).
  std::function<const session::TrialEnvironment*(QString& why)> claim;
  /// The session is over: the window takes the device back (its loop starts again).
  std::function<void()> release;
  std::function<void(const QString& what, const QString& detail)> error;
  std::function<bool(const QString& question)> confirm;
  std::function<QString(const QString& title, const QString& suggested)> ask_save_file;
  std::function<QString(const QString& title, const QString& filter)> ask_open_file;
};

class MentorTab final : public QWidget {
  Q_OBJECT

 public:
  /// `hand`, `paper` and `settings` must outlive every session (call shutdown() before they go).
  MentorTab(MouseHand& hand, PaperView& paper, QSettings& settings, MentorHost host, QWidget* parent = nullptr);
  ~MentorTab() override;

  // ---- Actions (the buttons call these); false when refused. --------------------------------
  /// Listen (lead) or connect (follow) with what the widgets say. A bad key file or address is
  /// refused with the library's message before the device is taken; nothing starts then.
  bool connectSession();
  /// Disconnect / stop listening: the session ends, its recording is kept.
  bool disconnectSession();
  /// Connect when idle, disconnect when a session runs (Space on this tab).
  void toggleSession();
  /// Saves the last session's recording (an existing file is replaced only when confirmed).
  bool saveRecording(const QString& file);
  /// While a session runs, at display rate (the main window's frame): the pens, the other's
  /// trail, the status; hands the device back when the session ended by itself.
  void frame();
  /// Ends a session without handing the device back (the window is closing).
  void shutdown();
  /// False if an unsaved recording exists and the person does not want to lose it.
  bool mayClose();
  /// Forgets the other station's trail on the paper.
  void clearPeerTrail();
  /// Lead or follow, as the role box would (its address shown).
  void setRole(net::MentorRole role);
  /// The passivity controller, the deadband and the station's counters (packets, energies, loop,
  /// clamps) in the engineer view only; plainly, the link and its round trip.
  void setEngineerView(bool on);

  [[nodiscard]] MentorSession& session() { return session_; }
  [[nodiscard]] bool running() const { return session_.active(); }
  /// The session's settings as the widgets say (the device is the window's, set at connect).
  [[nodiscard]] MentorSettings settingsFromWidgets() const;
  [[nodiscard]] const servo::LiveCounters* counters() const { return session_.counters(); }

  /// The widgets, so tests drive what a person drives.
  struct Widgets {
    QComboBox* role = nullptr;
    QLineEdit* address = nullptr;
    QComboBox* coupling = nullptr;
    QLineEdit* key_file = nullptr;
    QCheckBox* passivity = nullptr;
    QDoubleSpinBox* deadband = nullptr;
    QDoubleSpinBox* wait = nullptr;
    QPushButton* connect = nullptr;
    QPushButton* disconnect = nullptr;
    QPushButton* save = nullptr;
    QLabel* phase = nullptr;
    QLabel* status = nullptr;
    QLabel* clamps = nullptr;
    QLabel* recording = nullptr;
  };
  [[nodiscard]] const Widgets& widgets() const { return w_; }

 private:
  void buildUi();
  void buildChoices(QVBoxLayout* layout);
  void buildControls(QVBoxLayout* layout);
  void loadSettings();
  void saveSettings();
  void onRoleChanged();
  void sessionOver();
  void refresh();
  void refreshStatus();
  [[nodiscard]] net::MentorRole role() const;
  [[nodiscard]] QString peerLabel() const;
  [[nodiscard]] QString banner(const MentorSnapshot& snapshot) const;
  bool confirmDiscard(const QString& question);

  MouseHand& hand_;
  PaperView& paper_;
  QSettings& settings_;
  MentorHost host_;
  MentorSession session_;
  Widgets w_;
  QString listen_address_;   // each role's address, as last typed
  QString connect_address_;
  int shown_role_ = -1;      // the role whose address the field shows
  QElapsedTimer status_clock_;
  QFormLayout* form_ = nullptr;
  bool engineer_view_ = false;
};

}  // namespace hattr::studio
