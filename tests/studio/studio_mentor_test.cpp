// The studio's live mentoring: two MentorSessions in one process over real UDP sockets on
// loopback (the leader on an ephemeral port, the follower connecting to it) with a shared random
// key written to a key file, each on its own simulated pen held by its own mouse hand, in real
// time. Then the Mentor tab of the main window, offscreen, against a session in the same process:
// both pens drawn live (a screenshot, studio_mentor.png), a lost link, the recording saved.
// Every wait is for a condition with a generous deadline; no test counts wall-clock time tightly.

#include <QLabel>
#include <QLineEdit>
#include <QComboBox>
#include <QPushButton>
#include <QTabWidget>
#include <QtTest>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <thread>
#include <vector>

#include "core/mentor_session.hpp"
#include "core/mouse_hand.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/net/link_emulator.hpp"
#include "screen_checks.hpp"
#include "studio_test_support.hpp"
#include "ui/main_window.hpp"
#include "ui/mentor_tab.hpp"
#include "ui/paper_view.hpp"

using namespace hattr;
using namespace hattr::studio;
using test::colourNear;
using test::sendMouse;
using test::shareDrawn;

// Screenshots are kept in the working folder: ctest runs the test in its build folder.
#define HATTR_STUDIO_SCREENSHOT_DIR "."

namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kDeadline_s = 10.0;  // generous: the CI host is loaded

/// One station of the test: a mouse hand (moved by the test, as the GUI thread would) and a session.
struct Station {
  MouseHand hand;
  MentorSession session;

  void put(double x_m, double y_m, bool pen_down) {
    MouseInput input = hand.input();
    input.x_m = x_m;
    input.y_m = y_m;
    input.pen_down = pen_down;
    hand.setInput(input);
  }
  [[nodiscard]] bool linked() const {
    const MentorSnapshot s = session.snapshot();
    return s.phase == MentorPhase::kLinked && s.stats.link_up && session.peer().valid && session.ownPen().has_value();
  }
};

MentorSettings leaderSettings(const std::filesystem::path& key_file) {
  MentorSettings s;
  s.role = net::MentorRole::kLeader;
  s.address = "127.0.0.1:0";
  s.key_file = key_file;
  s.world = test::flatWorld();
  s.wait_s = kDeadline_s;
  return s;
}

MentorSettings followerSettings(const std::filesystem::path& key_file, const wire::UdpEndpoint& leader,
                                net::Coupling coupling, const std::string& device_uri = "sim://pen") {
  MentorSettings s;
  s.role = net::MentorRole::kFollower;
  s.address = leader.text();
  s.key_file = key_file;
  s.coupling = coupling;
  s.device_uri = device_uri;
  s.world = test::flatWorld();
  s.wait_s = kDeadline_s;
  return s;
}

/// Polls every station (as the display would) until `condition` holds; false after `timeout_s`.
bool pollUntil(std::initializer_list<Station*> stations, const std::function<bool()>& condition,
               double timeout_s = kDeadline_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (true) {
    for (Station* s : stations) (void)s->session.poll();
    if (condition()) return true;
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

/// Polls for `seconds` (time for pens to move; nothing is asserted about the time itself).
void pollFor(std::initializer_list<Station*> stations, double seconds) {
  (void)pollUntil(stations, [] { return false; }, seconds);
}

/// Distance in the paper plane between what `viewer` sees of the other pen and where it is [m].
double viewError(const Station& viewer, const Station& other) {
  return (viewer.session.peer().p_WT - other.session.ownPen()->p_WT).head<2>().norm();
}

double median(std::vector<double> v) {
  if (v.empty()) return 1e9;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// A point on a circle of radius `r` around (cx, cy) at phase `t` [s] of a 2 s turn.
Eigen::Vector2d onCircle(double cx, double cy, double r, double t) {
  return {cx + r * std::cos(kPi * t), cy + r * std::sin(kPi * t)};
}

/// Processes the window's events (its frame timer draws, polls and ends sessions) and polls
/// `others` until `condition` holds; false after `timeout_s`.
bool waitInWindow(std::initializer_list<Station*> others, const std::function<bool()>& condition,
                  double timeout_s = kDeadline_s) {
  QElapsedTimer timer;
  timer.start();
  while (!condition()) {
    if (static_cast<double>(timer.elapsed()) > timeout_s * 1e3) return false;
    for (Station* s : others) (void)s->session.poll();
    QTest::qWait(5);
  }
  return true;
}

QString allText(const QLabel* label) { return label->text(); }

}  // namespace

class StudioMentorTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    dir_ = test::freshTempDir("mentor");
    key_file_ = dir_ / "mentor.key";
    wire::writeKeyFile(key_file_, wire::randomKey(), false);
  }

  void cleanupTestCase() { std::filesystem::remove_all(dir_); }

  // (1) Once linked, each station's view of the other's pen is where that pen is: at rest, and
  // while both write circles on the paper.
  void eachStationSeesTheOthersPenWhereItIs() {
    Station leader, follower;
    leader.put(-0.015, 0.0, true);
    follower.put(0.015, 0.0, true);
    leader.session.start(leaderSettings(key_file_), leader.hand);
    follower.session.start(
        followerSettings(key_file_, leader.session.localEndpoint(), net::Coupling::kObserve), follower.hand);
    // The hand presses from the start, but the pen is held lifted while the loop's forces ramp in
    // (else it sinks into a paper not yet pushing back), and writes after.
    int early_samples = 0;
    bool touched_early = false;
    QVERIFY(pollUntil({&leader, &follower}, [&] {
      const std::optional<Sample>& pen = follower.session.ownPen();
      if (!pen) return false;
      if (follower.session.ownPenFresh() && pen->t_s < servo::SafetyConfig{}.ramp_time_s) {
        ++early_samples;
        touched_early = touched_early || pen->in_contact || pen->p_WT.z() < 0.0;
      }
      return pen->t_s > 0.6 && pen->in_contact;
    }));
    QVERIFY2(early_samples >= 3, qPrintable(QString::number(early_samples)));
    QVERIFY(!touched_early);
    QVERIFY2(pollUntil({&leader, &follower}, [&] { return leader.linked() && follower.linked(); }),
             mentorPhaseText(follower.session.snapshot()).c_str());

    // At rest: within 0.5 mm both ways.
    QVERIFY2(pollUntil({&leader, &follower},
                       [&] { return viewError(follower, leader) < 0.5e-3 && viewError(leader, follower) < 0.5e-3; }),
             qPrintable(QString("errors %1 mm, %2 mm")
                            .arg(viewError(follower, leader) * 1e3)
                            .arg(viewError(leader, follower) * 1e3)));

    // Writing: each hand draws a 10 mm circle for 2 s; each view is compared with the other pen.
    std::vector<double> follower_sees, leader_sees;
    double leader_x_min = 1.0, leader_x_max = -1.0, follower_x_min = 1.0, follower_x_max = -1.0;
    const auto begin = std::chrono::steady_clock::now();
    for (double t = 0.0; t < 2.0;
         t = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count()) {
      const Eigen::Vector2d a = onCircle(-0.025, 0.0, 0.010, t);
      const Eigen::Vector2d b = onCircle(0.025, 0.0, 0.010, t);
      leader.put(a.x(), a.y(), true);
      follower.put(b.x(), b.y(), true);
      (void)leader.session.poll();
      (void)follower.session.poll();
      follower_sees.push_back(viewError(follower, leader));
      leader_sees.push_back(viewError(leader, follower));
      leader_x_min = std::min(leader_x_min, leader.session.ownPen()->p_WT.x());
      leader_x_max = std::max(leader_x_max, leader.session.ownPen()->p_WT.x());
      follower_x_min = std::min(follower_x_min, follower.session.ownPen()->p_WT.x());
      follower_x_max = std::max(follower_x_max, follower.session.ownPen()->p_WT.x());
      std::this_thread::sleep_for(std::chrono::milliseconds(4));
    }
    const double follower_median = median(follower_sees), leader_median = median(leader_sees);
    qInfo("view error while writing (median): follower sees the leader %.3f mm, the leader sees the follower %.3f "
          "mm; round trip %.2f ms",
          follower_median * 1e3, leader_median * 1e3, follower.session.snapshot().stats.rtt_s * 1e3);
    // The pens really moved (so a view that stood still would fail), and the views followed them.
    QVERIFY2(leader_x_max - leader_x_min > 0.012, qPrintable(QString::number((leader_x_max - leader_x_min) * 1e3)));
    QVERIFY2(follower_x_max - follower_x_min > 0.012,
             qPrintable(QString::number((follower_x_max - follower_x_min) * 1e3)));
    QVERIFY2(follower_median < 2e-3, qPrintable(QString("follower's view: %1 mm").arg(follower_median * 1e3)));
    QVERIFY2(leader_median < 2e-3, qPrintable(QString("leader's view: %1 mm").arg(leader_median * 1e3)));
    // Both pens are on the paper and each side drew the other's trail.
    QVERIFY(follower.session.peer().pen_down);
    QVERIFY(leader.session.peer().pen_down);
    QVERIFY(follower.session.peerTrail().pointCount() > 20);
    QVERIFY(leader.session.peerTrail().pointCount() > 20);
    // The status has packets both ways and a round trip.
    const net::MentorStats fs = follower.session.snapshot().stats;
    QVERIFY(fs.peers_received > 100 && fs.peers_sent > 100);
    QVERIFY(fs.rtt_s > 0.0);
    follower.session.stop();
    leader.session.stop();
    QVERIFY(!follower.session.active() && !leader.session.active());
    QVERIFY(follower.session.recording().has_value());
    QVERIFY(follower.session.recording()->metadata().extra.count("failed") == 0);
  }

  // (2) With the position coupling the follower's pen is pulled toward the leader's; observing,
  // it stays where its hand holds it. The leader feels nothing in either.
  void thePositionCouplingPullsTheFollowersPenTowardTheLeaders() {
    double pulled_observe = 0.0, pulled_position = 0.0, guide_x = 0.0;
    QVERIFY(pulledToward(net::Coupling::kObserve, pulled_observe, guide_x));
    QVERIFY(pulledToward(net::Coupling::kPosition, pulled_position, guide_x));
    qInfo("follower's pen pulled toward the leader's: %.2f mm observing, %.2f mm with position (guidance %.2f N)",
          pulled_observe * 1e3, pulled_position * 1e3, guide_x);
    QVERIFY2(std::abs(pulled_observe) < 1e-3, qPrintable(QString::number(pulled_observe * 1e3)));
    QVERIFY2(pulled_position > 3e-3, qPrintable(QString::number(pulled_position * 1e3)));
    QVERIFY2(guide_x < -0.1, qPrintable(QString::number(guide_x)));  // toward the leader (−x)
  }

  // (3) The leader disconnects: its goodbye ends the follower's session normally (as `hattr
  // mentor` ends it), within a bound, and both recordings are kept, neither marked failed.
  void theLeadersDisconnectEndsTheFollowersSessionNormally() {
    Station leader, follower;
    leader.put(-0.01, 0.0, true);
    follower.put(0.01, 0.0, true);
    leader.session.start(leaderSettings(key_file_), leader.hand);
    follower.session.start(
        followerSettings(key_file_, leader.session.localEndpoint(), net::Coupling::kPosition), follower.hand);
    QVERIFY(pollUntil({&leader, &follower}, [&] { return leader.linked() && follower.linked(); }));
    pollFor({&leader, &follower}, 0.5);  // something to record

    leader.session.stop();
    QElapsedTimer timer;
    timer.start();
    QVERIFY(pollUntil({&follower}, [&] { return !follower.session.active(); }));
    const qint64 took_ms = timer.elapsed();
    const MentorSnapshot s = follower.session.snapshot();
    qInfo("follower ended %lld ms after the leader's goodbye: %s", static_cast<long long>(took_ms),
          mentorPhaseText(s).c_str());
    QVERIFY2(took_ms < 5000, qPrintable(QString::number(took_ms)));
    QVERIFY2(s.failure.empty(), s.failure.c_str());
    QVERIFY(s.ended_by_other);
    QCOMPARE(mentorPhaseText(s), std::string("the other station ended the session"));
    QVERIFY(follower.session.recording().has_value() && leader.session.recording().has_value());
    QVERIFY(follower.session.recording()->duration_s() > 0.3);
    QVERIFY(follower.session.recording()->metadata().extra.count("failed") == 0);
    QVERIFY(leader.session.recording()->metadata().extra.count("failed") == 0);
  }

  // (3) The network between the stations goes (a relay in between stops): the follower says
  // "link lost" within a bound, and so does the leader; each keeps its recording, marked failed;
  // it is saved as a haptic profile, not replaced unasked, replaced when confirmed.
  void aCutLinkIsReportedLostAndTheRecordingKeptMarkedFailed() {
    Station leader, follower;
    leader.put(-0.01, 0.0, true);
    follower.put(0.01, 0.0, true);
    leader.session.start(leaderSettings(key_file_), leader.hand);
    net::LinkRelay relay("127.0.0.1:0", leader.session.localEndpoint().text(), {}, {});
    follower.session.start(followerSettings(key_file_, relay.endpoint(), net::Coupling::kBilateral), follower.hand);
    QVERIFY(pollUntil({&leader, &follower}, [&] { return leader.linked() && follower.linked(); }));
    pollFor({&leader, &follower}, 0.5);  // something to record
    QVERIFY(follower.linked());

    relay.stop();  // no goodbye gets through any more
    QElapsedTimer timer;
    timer.start();
    QVERIFY(pollUntil({&leader, &follower}, [&] { return !follower.session.active() && !leader.session.active(); }));
    const qint64 took_ms = timer.elapsed();
    const MentorSnapshot s = follower.session.snapshot();
    qInfo("both ended within %lld ms of the cut: %s", static_cast<long long>(took_ms), s.failure.c_str());
    QVERIFY2(took_ms < 5000, qPrintable(QString::number(took_ms)));
    QCOMPARE(s.phase, MentorPhase::kEnded);
    QVERIFY2(s.failure.starts_with("link lost"), s.failure.c_str());
    QVERIFY(!s.ended_by_other);
    QVERIFY(s.stats.link_faults >= 1);
    QVERIFY(mentorPhaseText(s).starts_with("link lost"));
    QVERIFY2(leader.session.snapshot().failure.starts_with("link lost"), leader.session.snapshot().failure.c_str());

    // Each recording is kept, marked failed.
    QVERIFY(follower.session.recording().has_value() && leader.session.recording().has_value());
    const HapticProfile& kept = *follower.session.recording();
    QVERIFY2(kept.duration_s() > 0.3, qPrintable(QString::number(kept.duration_s())));
    QCOMPARE(kept.metadata().extra.at("failed"), s.failure);
    QCOMPARE(kept.metadata().extra.at("mentor_role"), std::string("follower"));
    QCOMPARE(kept.metadata().extra.at("coupling"), std::string("bilateral"));
    QVERIFY(leader.session.recording()->metadata().extra.count("failed") == 1);
    QVERIFY(!follower.session.recordingSaved());

    // Saved; not replaced unasked; replaced when confirmed; read back with its failure.
    const auto file = dir_ / "trainee.csv";
    QCOMPARE(follower.session.saveRecording(file, false), SaveOutcome::kSaved);
    QVERIFY(follower.session.recordingSaved());
    std::filesystem::resize_file(file, 10);
    QCOMPARE(follower.session.saveRecording(file, false), SaveOutcome::kNeedsConfirmation);
    QCOMPARE(std::filesystem::file_size(file), std::uintmax_t{10});
    QCOMPARE(follower.session.saveRecording(file, true), SaveOutcome::kSaved);
    const HapticProfile back = io::readProfileCsv(file);
    QCOMPARE(back.size(), kept.size());
    QCOMPARE(back.metadata().extra.at("failed"), s.failure);
  }

  // A second follower is refused and says so; a station nobody answers (or a wrong key) gives up
  // after the wait, saying so; neither records anything.
  void aBusyLeaderAndNoAnswerEndTheSessionSayingSo() {
    Station leader, first, second;
    leader.session.start(leaderSettings(key_file_), leader.hand);
    const auto at = leader.session.localEndpoint();
    first.session.start(followerSettings(key_file_, at, net::Coupling::kObserve), first.hand);
    QVERIFY(pollUntil({&leader, &first}, [&] { return leader.linked() && first.linked(); }));
    second.session.start(followerSettings(key_file_, at, net::Coupling::kObserve), second.hand);
    QVERIFY(pollUntil({&leader, &first, &second}, [&] { return !second.session.active(); }));
    const std::string refused = second.session.snapshot().failure;
    QVERIFY2(refused.find("already mentors another follower") != std::string::npos, refused.c_str());
    QVERIFY(!second.session.recording().has_value());
    QVERIFY(first.session.snapshot().stats.link_up);
    QVERIFY(leader.session.snapshot().stats.busy_refusals >= 1);
    first.session.stop();
    leader.session.stop();

    // Nobody answers: a socket that never replies (so no ICMP either).
    auto silent = wire::UdpSocket::bound({.address = 0x7F000001u, .port = 0});
    Station lonely;
    MentorSettings settings = followerSettings(key_file_, silent.localEndpoint(), net::Coupling::kObserve);
    settings.wait_s = 0.5;
    lonely.session.start(settings, lonely.hand);
    QVERIFY(pollUntil({&lonely}, [&] { return !lonely.session.active(); }));
    const std::string alone = lonely.session.snapshot().failure;
    QVERIFY2(alone.starts_with("no other station within 0.5 s"), alone.c_str());
    QVERIFY(!lonely.session.recording().has_value());

    // A wrong key looks the same: the leader drops the packets unanswered (and counts them).
    const auto other_key = dir_ / "other.key";
    wire::writeKeyFile(other_key, wire::randomKey(), true);
    Station host, stranger;
    host.session.start(leaderSettings(key_file_), host.hand);
    settings = followerSettings(other_key, host.session.localEndpoint(), net::Coupling::kObserve);
    settings.wait_s = 0.5;
    stranger.session.start(settings, stranger.hand);
    QVERIFY(pollUntil({&host, &stranger}, [&] { return !stranger.session.active(); }));
    QVERIFY(stranger.session.snapshot().failure.starts_with("no other station"));
    QVERIFY(host.session.snapshot().stats.drops[static_cast<std::size_t>(wire::DropReason::kBadMac)] >= 1);
    QCOMPARE(host.session.snapshot().phase, MentorPhase::kWaiting);
    host.session.stop();
  }

  // (4) A bad key file or a bad address: the library's message, and nothing starts (no loop, no
  // socket: the port asked for is still free).
  void aBadKeyFileOrAddressGivesTheLibrarysMessageAndStartsNothing() {
    const auto missing = dir_ / "missing.key";
    const auto short_key = dir_ / "short.key";
    std::ofstream(short_key) << "abc\n";
    std::filesystem::permissions(short_key, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write,
                                 std::filesystem::perm_options::replace);
    const auto libraryMessage = [](const std::function<void()>& call) {
      try {
        call();
      } catch (const InputError& e) {
        return std::string(e.what());
      }
      return std::string("(nothing thrown)");
    };
    // A port that is free now (bound and released).
    std::uint16_t port = 0;
    {
      auto probe = wire::UdpSocket::bound({.address = 0x7F000001u, .port = 0});
      port = probe.localEndpoint().port;
    }
    const std::string at = "127.0.0.1:" + std::to_string(port);

    struct Case {
      std::string what;
      MentorSettings settings;
      std::string expected;  // the library's message
    };
    std::vector<Case> cases;
    MentorSettings s = leaderSettings(missing);
    s.address = at;
    cases.push_back({"missing key file", s, libraryMessage([&] { (void)wire::readKeyFile(missing); })});
    s.key_file = short_key;
    cases.push_back({"short key file", s, libraryMessage([&] { (void)wire::readKeyFile(short_key); })});
    s.key_file = key_file_;
    s.address = "127.0.0.1:notaport";
    cases.push_back({"bad listen address", s,
                     libraryMessage([&] { (void)wire::parseUdpEndpoint(s.address, "listen address", 0); })});
    MentorSettings f = followerSettings(key_file_, {.address = 0x7F000001u, .port = 7400}, net::Coupling::kObserve);
    f.address = "expert-host:7400";
    cases.push_back({"bad leader address", f,
                     libraryMessage([&] { (void)wire::parseUdpEndpoint(f.address, "leader's address"); })});
    for (const Case& c : cases) {
      Station station;
      const std::string got = libraryMessage([&] { station.session.start(c.settings, station.hand); });
      QVERIFY2(got == c.expected, qPrintable(QString::fromStdString(c.what + ": got \"" + got + "\", expected \"" +
                                                                    c.expected + "\"")));
      QVERIFY(!station.session.active());
      QCOMPARE(station.session.snapshot().phase, MentorPhase::kIdle);
      QVERIFY(station.session.counters() == nullptr);
    }
    QVERIFY(cases[0].expected.find("missing.key") != std::string::npos);
    QVERIFY(cases[1].expected.find("expected 64 hexadecimal characters") != std::string::npos);
    QVERIFY(cases[2].expected.starts_with("listen address: port"));
    QVERIFY(cases[3].expected.starts_with("leader's address: host"));
    // Nothing was bound: the port is still free.
    auto again = wire::UdpSocket::bound({.address = 0x7F000001u, .port = port});
    QCOMPARE(again.localEndpoint().port, port);
  }

  // (5) The Mentor tab: the window is the trainee, a session in this process the expert. Both
  // write; the paper shows the trainee's own pen and trail in ink and the expert's in the peer
  // colour, live (screenshot studio_mentor.png); the window's own loop is off meanwhile.
  void theMentorTabShowsBothPensLive() {
    MainWindow w(settingsFile("follow.ini"));
    w.setInteractive(false);
    w.resize(1280, 820);
    w.show();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    QCOMPARE(w.tabs()->count(), 7);
    QCOMPARE(w.tabs()->tabText(MainWindow::kTabMentor), QStringLiteral("Mentor"));
    QVERIFY(w.mentorTab() != nullptr);
    QCOMPARE(w.tabs()->widget(MainWindow::kTabMentor), static_cast<QWidget*>(w.mentorTab()));
    QVERIFY(w.rig().active());

    Station expert;
    expert.put(-0.025, 0.0, true);
    expert.session.start(leaderSettings(key_file_), expert.hand);

    // The person: Follow, the expert's address, the key, observe; Connect.
    MentorTab& tab = *w.mentorTab();
    w.tabs()->setCurrentIndex(MainWindow::kTabMentor);
    tab.setRole(net::MentorRole::kFollower);
    QCOMPARE(tab.widgets().connect->text(), QStringLiteral("Connect"));
    QVERIFY(tab.widgets().coupling->isEnabled());
    tab.widgets().address->setText(QString::fromStdString(expert.session.localEndpoint().text()));
    tab.widgets().key_file->setText(QString::fromStdString(key_file_.string()));
    tab.widgets().coupling->setCurrentIndex(0);
    PaperView* view = w.paperView();
    const Eigen::Vector2d start = onCircle(0.025, 0.0, 0.010, 0.0);
    sendMouse(view, QEvent::MouseMove, view->mapping().toWidget(start.x(), start.y()), Qt::NoButton, Qt::NoButton);
    tab.widgets().connect->click();
    QVERIFY2(tab.running(), qPrintable(w.lastError()));
    QCOMPARE(w.activity(), MainWindow::Activity::kMentoring);
    QVERIFY2(!w.rig().active(), "the window's own loop must not run with the mentoring station");
    // The other tabs' actions are refused meanwhile: one loop drives the device and the hand.
    QVERIFY(!w.startRecording());
    QVERIFY(!w.setDevice(QStringLiteral("sim://pen")));
    QVERIFY(!w.rig().active());
    QVERIFY2(allText(tab.widgets().phase).startsWith("connecting to 127.0.0.1:"), qPrintable(tab.widgets().phase->text()));
    QVERIFY(!tab.widgets().connect->isEnabled() && tab.widgets().disconnect->isEnabled());

    // Both write circles, the expert on the left, the person (the mouse on the paper) on the right.
    sendMouse(view, QEvent::MouseButtonPress, view->mapping().toWidget(start.x(), start.y()), Qt::LeftButton,
              Qt::LeftButton);
    QElapsedTimer timer;
    timer.start();
    double linked_at_s = -1.0;
    const auto write = [&] {
      const double t = static_cast<double>(timer.elapsed()) * 1e-3;
      const Eigen::Vector2d a = onCircle(-0.025, 0.0, 0.010, t);
      const Eigen::Vector2d b = onCircle(0.025, 0.0, 0.010, t);
      expert.put(a.x(), a.y(), true);
      sendMouse(view, QEvent::MouseMove, view->mapping().toWidget(b.x(), b.y()), Qt::NoButton, Qt::LeftButton);
      if (linked_at_s < 0.0 && tab.session().snapshot().phase == MentorPhase::kLinked) linked_at_s = t;
      return linked_at_s >= 0.0 && t - linked_at_s > 1.6;  // most of a circle each, once linked
    };
    QVERIFY2(waitInWindow({&expert}, write), mentorPhaseText(tab.session().snapshot()).c_str());
    QTest::qWait(50);  // a frame or two more
    (void)expert.session.poll();
    QVERIFY(tab.session().snapshot().stats.link_up);

    // The screenshot, mid-writing: both pens on the paper.
    const QImage shot = w.grab().toImage();
    const net::PeerView peer_at_shot = tab.session().peer();
    QVERIFY(shot.save(QString::fromStdString((dir_ / "studio_mentor.png").string())));
    const QString kept_shot = QStringLiteral(HATTR_STUDIO_SCREENSHOT_DIR "/studio_mentor.png");
    QVERIFY(shot.save(kept_shot));
    qInfo("screenshot: %s", qPrintable(kept_shot));

    // The status: link, round trip, packets, energies, clamps.
    QTest::qWait(300);
    const QString status = tab.widgets().status->text();
    for (const char* part : {"<b>Link</b> up", "round trip", "<b>Packets</b> in", "lost", "<b>Energy</b> in",
                             "dissipated", "link faults"}) {
      QVERIFY2(status.contains(QLatin1String(part)), qPrintable(part + QStringLiteral(" in: ") + status));
    }
    QVERIFY2(tab.widgets().clamps->text().startsWith("Clamped to the device"), qPrintable(tab.widgets().clamps->text()));
    QVERIFY2(allText(tab.widgets().phase).startsWith("linked: coupling observe"), qPrintable(tab.widgets().phase->text()));

    // Stop both (the person disconnects first), then check the shot against where the pens were.
    sendMouse(view, QEvent::MouseButtonRelease, view->mapping().toWidget(start.x(), start.y()), Qt::LeftButton,
              Qt::NoButton);
    QVERIFY(tab.disconnectSession());
    expert.session.stop();
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QVERIFY2(w.rig().active(), "the window's loop is back after the session");
    QVERIFY(tab.widgets().save->isEnabled());
    QVERIFY(tab.session().recording().has_value() && expert.session.recording().has_value());
    const double expert_drawn = shareDrawn(shot, w, *expert.session.recording(), PaperColours::peer());
    const double own_drawn = shareDrawn(shot, w, *tab.session().recording(), PaperColours::ink());
    qInfo("drawn: the expert's pen-down points in the peer colour %.2f, the person's in ink %.2f", expert_drawn,
          own_drawn);
    QVERIFY2(expert_drawn > 0.6, qPrintable(QString::number(expert_drawn)));
    QVERIFY2(own_drawn > 0.6, qPrintable(QString::number(own_drawn)));
    // The expert's pen itself, where the window last heard it.
    const QPoint origin = view->mapTo(&w, QPoint(0, 0));
    QVERIFY(peer_at_shot.valid && peer_at_shot.pen_down);
    QVERIFY(colourNear(shot, (view->mapping().toWidget(peer_at_shot.p_WT) + QPointF(origin)).toPoint(),
                       PaperColours::peer(), 3));
  }

  // The window leads: "listening on", a follower links (through a relay), then the network goes:
  // the tab says "link lost", the window gets its loop back, the recording is kept (failed) and
  // saved, an existing file is not replaced unasked. A bad key file is refused with the
  // library's message before the window's loop is touched.
  void theWindowLeadsAndALostLinkKeepsTheRecording() {
    MainWindow w(settingsFile("lead.ini"));
    w.setInteractive(false);
    w.show();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    MentorTab& tab = *w.mentorTab();
    w.tabs()->setCurrentIndex(MainWindow::kTabMentor);
    tab.setRole(net::MentorRole::kLeader);
    QCOMPARE(tab.widgets().address->text(), QString::fromLatin1(kDefaultListenAddress));
    QCOMPARE(tab.widgets().connect->text(), QStringLiteral("Listen"));
    QVERIFY(!tab.widgets().coupling->isEnabled());  // the follower names the coupling

    // A bad key file: the library's message, nothing started, the window's loop untouched.
    tab.widgets().address->setText(QStringLiteral("127.0.0.1:0"));
    tab.widgets().key_file->setText(QString::fromStdString((dir_ / "nope.key").string()));
    QVERIFY(!tab.connectSession());
    std::string expected;
    try {
      (void)wire::readKeyFile(dir_ / "nope.key");
    } catch (const InputError& e) {
      expected = e.what();
    }
    QVERIFY2(w.lastError().contains(QString::fromStdString(expected)), qPrintable(w.lastError()));
    QCOMPARE(w.activity(), MainWindow::Activity::kFree);
    QVERIFY(w.rig().active());
    QVERIFY(!tab.running());

    // Listen; a trainee's station links.
    tab.widgets().key_file->setText(QString::fromStdString(key_file_.string()));
    w.primaryAction();  // Space on this tab
    QVERIFY2(tab.running(), qPrintable(w.lastError()));
    QVERIFY2(allText(tab.widgets().phase).startsWith("listening on 127.0.0.1:"), qPrintable(tab.widgets().phase->text()));
    QCOMPARE(tab.widgets().disconnect->text(), QStringLiteral("Stop listening"));
    Station trainee;
    trainee.put(0.01, 0.0, true);
    net::LinkRelay relay("127.0.0.1:0", tab.session().localEndpoint().text(), {}, {});
    trainee.session.start(followerSettings(key_file_, relay.endpoint(), net::Coupling::kPosition), trainee.hand);
    QVERIFY(waitInWindow({&trainee}, [&] { return tab.session().snapshot().phase == MentorPhase::kLinked; }));
    QVERIFY(waitInWindow({&trainee}, [&] { return tab.session().snapshot().linked_s > 0.5; }));

    // The network goes (no goodbye gets through): link lost, recording kept.
    relay.stop();
    QVERIFY(waitInWindow({}, [&] { return w.activity() == MainWindow::Activity::kFree; }));
    QVERIFY(!tab.running());
    QVERIFY(w.rig().active());
    QVERIFY2(w.lastError().contains("link lost"), qPrintable(w.lastError()));
    QVERIFY2(allText(tab.widgets().phase).startsWith("link lost"), qPrintable(tab.widgets().phase->text()));
    QVERIFY(tab.session().recording().has_value());
    QVERIFY(tab.session().recording()->metadata().extra.count("failed") == 1);
    QVERIFY2(tab.widgets().recording->text().contains("marked failed"), qPrintable(tab.widgets().recording->text()));
    QVERIFY(tab.widgets().save->isEnabled());

    // Saved; saving again over it is refused (the question is answered no).
    const QString file = QString::fromStdString((dir_ / "expert.csv").string());
    QVERIFY2(tab.saveRecording(file), qPrintable(w.lastError()));
    const auto size = std::filesystem::file_size(file.toStdString());
    QVERIFY(!tab.saveRecording(file));
    QCOMPARE(std::filesystem::file_size(file.toStdString()), size);
    QCOMPARE(io::readProfileCsv(file.toStdString()).metadata().extra.at("mentor_role"), std::string("leader"));
  }

 private:
  /// Whether `coupling` pulls the follower's pen toward the leader's: how far [m] the resting
  /// follower pen sits from its hand toward the leader's pen, and the guidance force's x [N].
  bool pulledToward(net::Coupling coupling, double& pulled_m, double& guide_x_N) {
    Station leader, follower;
    const double leader_x = -0.010, follower_x = 0.010;
    leader.put(leader_x, 0.0, false);
    follower.put(follower_x, 0.0, false);
    leader.session.start(leaderSettings(key_file_), leader.hand);
    // A loose grip (80 N/m), as the library's mentoring tests use, so a coupling can move the pen.
    follower.session.start(followerSettings(key_file_, leader.session.localEndpoint(), coupling,
                                            "sim://pen?hand_stiffness_N_per_m=80"),
                           follower.hand);
    if (!pollUntil({&leader, &follower}, [&] { return leader.linked() && follower.linked(); })) return false;
    // Settled: past the coupling's fade-in, the follower's pen at rest.
    if (!pollUntil({&leader, &follower}, [&] {
          return follower.session.snapshot().linked_s > 0.6 && follower.session.ownPen()->v_WT.head<2>().norm() < 2e-3;
        })) {
      return false;
    }
    pulled_m = follower_x - follower.session.ownPen()->p_WT.x();
    guide_x_N = follower.session.ownPen()->f_guide_W.x();
    const double leader_moved_m = std::abs(leader.session.ownPen()->p_WT.x() - leader_x);
    follower.session.stop();
    leader.session.stop();
    if (leader_moved_m > 1e-3) {
      qWarning("the leader's pen moved %.2f mm", leader_moved_m * 1e3);
      return false;
    }
    return true;
  }

  /// The window's settings, in the engineer view: these tests read the station's counters.
  std::unique_ptr<QSettings> settingsFile(const char* name) const {
    auto settings = std::make_unique<QSettings>(QString::fromStdString((dir_ / name).string()), QSettings::IniFormat);
    settings->setValue("view/engineer", true);
    return settings;
  }

  std::filesystem::path dir_;
  std::filesystem::path key_file_;
};

QTEST_MAIN(StudioMentorTest)
#include "studio_mentor_test.moc"
