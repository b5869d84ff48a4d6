// hattr mentor lead | follow | simulate: live mentoring between two stations over the network
// (docs/mentoring.md), and the two-station simulation that measures the couplings under delay.

#include <csignal>
#include <optional>
#include <iostream>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/net/mentor_station.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/ops/mentor_station_run.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace hattr::cli {
namespace {

volatile std::sig_atomic_t g_mentor_stop = 0;
extern "C" void onMentorStop(int) { g_mentor_stop = 1; }

struct MentorOptions {
  std::string address;       // lead: --listen; follow: --connect
  std::string key;
  std::string device = "sim://pen";
  std::string coupling = "observe";
  std::string hand;          // a profile the simulated hand writes once the link is up
  std::string record;
  std::string record_dir;    // lead serving sessions: one profile per session
  int sessions = 1;          // lead: sessions to serve (0: until interrupted)
  double seconds = 0.0;      // 0: the hand script's length + 0.5 s, or until the session ends
  double wait_s = 30.0;
  bool no_passivity = false;
  double deadband = 0.0;
  bool force = false;
  bool json = false;
};

/// Where session `number` (from 1) is written: --record for one session, else
/// --record-dir/session-NNN.csv; empty when neither is given.
std::string recordPath(const MentorOptions& opt, int number) {
  if (!opt.record_dir.empty()) return (std::filesystem::path(opt.record_dir) / fmt::format("session-{:03}.csv", number)).string();
  return opt.record;
}

/// Checks the recording options before anything runs.
void checkRecordOptions(const MentorOptions& opt, bool serving) {
  HATTR_THROW_UNLESS(!serving || opt.record.empty(), "--record: with --sessions {} each session is its own file: use "
                     "--record-dir DIR", opt.sessions);
  if (!opt.record.empty()) checkOutputFiles({opt.record}, opt.force);
  if (!opt.record_dir.empty()) {
    checkOutputFolder(opt.record_dir, {"session-001.csv"}, opt.force);  // sessions are numbered from 1
    std::filesystem::create_directories(opt.record_dir);
  }
}

/// Waits for the other station (polling the run's link watch); true once linked, false when it
/// refused, nobody came in time or we were interrupted.
bool waitForLink(ops::MentorStationRun& run) {
  while (!run.ended() && !g_mentor_stop) {
    if (run.poll(ops::MentorStationRun::Clock::now())) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

/// A linked session: until the time is up, the other station says goodbye, the link stays down
/// too long (lost), or we are interrupted.
void runLinkedSession(ops::MentorStationRun& run, double duration_s) {
  const auto end = ops::MentorStationRun::Clock::now() + std::chrono::duration<double>(duration_s);
  while (ops::MentorStationRun::Clock::now() < end && !g_mentor_stop && !run.ended()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    (void)run.poll(ops::MentorStationRun::Clock::now());
  }
  run.endNow();
}

/// Writes a session's recording where it goes; a failure to write is said and added to the
/// session's (the station goes on). Returns the session's JSON with its file.
nlohmann::json keepSession(const MentorOptions& opt, int number, net::MentorRole role, ops::MentorSessionOutcome& outcome) {
  std::string file = outcome.recording.empty() ? "" : recordPath(opt, number);
  std::string failure = outcome.failure;
  if (!file.empty()) {
    try {
      writeRecording(outcome.recording, file, opt.force);
    } catch (const std::exception& e) {  // kept elsewhere (or not at all): said, and the station goes on
      std::cerr << "hattr: " << e.what() << '\n';
      failure += (failure.empty() ? "" : "; ") + std::string(e.what());
      file.clear();
    }
  }
  const net::MentorStats& s = outcome.stats;
  if (!opt.json) {
    std::cout << fmt::format("{}: {} samples recorded, {} packets in, {} out, {} lost, {} link faults, energy in {:.4f} J "
                             "out {:.4f} J{}{}\n",
                             net::roleName(role), outcome.recording.size(), s.peers_received, s.peers_sent, s.lost,
                             s.link_faults, s.energy_in_J, s.energy_out_J, file.empty() ? "" : "; written to " + file,
                             outcome.failure.empty() ? "" : "; failed: " + outcome.failure)
              << std::flush;
  }
  nlohmann::json json = outcome.toJson();
  json["file"] = file;
  json["failure"] = failure;
  return json;
}

// One station, live (ops::MentorStationRun): wait for the other, release the hand, record, stop
// on a lost link; a lead with --sessions other than 1 then waits for the next follower (a
// study's next trial).
void runStation(const MentorOptions& opt, net::MentorRole role) {
  const bool serving = role == net::MentorRole::kLeader && opt.sessions != 1;
  // The simulated hand (if any) waits, lifted, until both stations are linked.
  std::optional<HapticProfile> script;
  std::unique_ptr<device::ProfileHandScript> script_hand;
  if (!opt.hand.empty()) {
    script = io::readProfileCsv(opt.hand);
    script_hand = std::make_unique<device::ProfileHandScript>(*script);
  }
  // A lead serving sessions waits for each without limit.
  ops::MentorStationRun run({.role = role, .address = opt.address, .key_file = opt.key,
                             .coupling = net::parseCoupling(opt.coupling), .passivity = !opt.no_passivity,
                             .deadband = opt.deadband, .device_uri = opt.device, .wait_s = serving ? -1.0 : opt.wait_s,
                             .listen_what = "--listen", .connect_what = "--connect", .key_what = "--key"},
                            script_hand.get(), ops::MentorStationRun::HandStart::kHeldUntilLinked);
  checkRecordOptions(opt, serving);  // after the key, the address and the port: nothing made for a station that cannot run
  for (const auto& c : run.station().clamps()) std::cerr << "hattr: clamped: " << c << '\n';
  std::signal(SIGINT, onMentorStop);
  std::signal(SIGTERM, onMentorStop);
  std::cout << run.where() << std::endl;

  // Session after session (one for a follower): the hands start together once linked (after
  // the coupling's fade-in), both sides record; whatever was recorded is kept, failure or not.
  nlohmann::json sessions = nlohmann::json::array();
  std::string first_failure;
  for (int number = 1; !g_mentor_stop && (opt.sessions == 0 || number <= opt.sessions); ++number) {
    if (number > 1) run.nextSession(ops::MentorStationRun::Clock::now());
    const bool linked = waitForLink(run);
    if (!linked && g_mentor_stop) break;
    if (linked) {
      std::cout << "linked: coupling "
                << (role == net::MentorRole::kFollower ? opt.coupling : std::string("as the follower asks"))
                << (serving ? fmt::format(" (session {})", number) : "") << std::endl;
      const double duration_s = opt.seconds > 0.0 ? opt.seconds
                                : (script && !serving ? script->duration_s() + run.mentor().ramp_s + 0.5 : 1e9);
      runLinkedSession(run, duration_s);
    }
    ops::MentorSessionOutcome outcome = run.takeSession();
    if (first_failure.empty()) first_failure = outcome.failure;
    sessions.push_back(keepSession(opt, number, role, outcome));
    if (!serving || run.loopStopped()) break;
  }
  run.close();

  if (opt.json) {
    nlohmann::json out = {{"role", std::string(net::roleName(role))}, {"coupling", opt.coupling}};
    if (serving) {
      out["sessions"] = sessions;
    } else if (!sessions.empty()) {
      out.update(sessions.front());
    }
    printJson(out);
  }
  // One session: a failure is the command's. Serving: each session's failure was said, and kept.
  if (!serving && !first_failure.empty()) {
    throw Error(first_failure + (opt.record.empty() ? "" : "; what was recorded is in " + opt.record));
  }
}

struct SimulateOptions {
  std::string couplings = "observe,position,force,bilateral";
  std::string rtt_ms = "0,10,50,100,200";
  std::string loss_percent = "0,5";
  std::string passivity = "both";
  std::string deadband = "0";
  double seconds = 0.0;
  std::string glyph = "na";
  std::uint64_t seed = 1;
  std::string expert_device = "sim://pen";
  std::string trainee_device = "sim://pen?hand_stiffness_N_per_m=80";
  bool json = false;
};

std::vector<double> numberList(const std::string& text, const char* option) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    HATTR_THROW_UNLESS(!item.empty() && end && *end == '\0' && std::isfinite(v) && v >= 0.0,
                       "{}: expected comma-separated numbers >= 0, got \"{}\"", option, item);
    out.push_back(v);
  }
  return out;
}

// The table of docs/mentoring.md: coupling × round trip × loss, with the passivity method on and off.
void runSimulate(const SimulateOptions& opt) {
  const sim::Glyph glyph = sim::findGlyph(opt.glyph);
  const HapticProfile plan = sim::expertScript(glyph);
  std::vector<bool> passivity_settings;
  if (opt.passivity != "off") passivity_settings.push_back(true);
  if (opt.passivity != "on") passivity_settings.push_back(false);
  nlohmann::json rows = nlohmann::json::array();
  if (!opt.json) {
    std::cout << fmt::format("{:<10} {:>7} {:>6} {:>10} {:>9} {:>14} {:>11} {:>13} {:>14} {:>11} {:>9}\n", "coupling",
                             "rtt_ms", "loss", "passivity", "deadband", "tracking_mm", "force_N", "energy_J",
                             "dissipated_J", "peak_N", "packets/s");
  }
  std::stringstream couplings(opt.couplings);
  std::string name;
  while (std::getline(couplings, name, ',')) {
    const net::Coupling coupling = net::parseCoupling(name);
    for (const double rtt : numberList(opt.rtt_ms, "--rtt-ms")) {
      for (const double loss : numberList(opt.loss_percent, "--loss-percent")) {
        for (const bool passivity : passivity_settings) {
          if (!passivity && coupling != net::Coupling::kBilateral) continue;  // it acts on bilateral only
          for (const double deadband : numberList(opt.deadband, "--deadband")) {
          device::ProfileHandScript expert(plan);
          net::LaggingHand trainee(plan);
          const net::MentoredRun run = net::runMentoredSimulation(
              {.coupling = coupling, .passivity = passivity, .round_trip_s = rtt * 1e-3, .loss = loss / 100.0,
               .deadband = deadband, .seed = opt.seed, .duration_s = opt.seconds > 0.0 ? opt.seconds : plan.duration_s() + 0.3,
               .settle_s = 0.8, .leader_device = opt.expert_device, .follower_device = opt.trainee_device},
              expert, trainee);
          rows.push_back({{"coupling", name}, {"rtt_ms", rtt}, {"loss_percent", loss}, {"passivity", passivity},
                          {"tracking_rms_mm", run.tracking_rms_m * 1e3}, {"force_rms_N", run.force_rms_N},
                          {"energy_generated_J", run.energy_generated_J}, {"dissipated_J", run.dissipated_J},
                          {"peak_coupling_force_N", run.peak_coupling_force_N}, {"faults", run.faults},
                          {"link_faults", run.link_faults}, {"deadband", deadband},
                          {"packets_per_s", run.packets_per_s}});
          if (!opt.json) {
            std::cout << fmt::format("{:<10} {:>7g} {:>5g}% {:>10} {:>9g} {:>14.2f} {:>11.3f} {:>+13.4f} {:>14.4f} {:>11.2f} "
                                     "{:>9.0f}\n",
                                     name, rtt, loss, passivity ? "on" : "off", deadband, run.tracking_rms_m * 1e3,
                                     run.force_rms_N, run.energy_generated_J, run.dissipated_J,
                                     run.peak_coupling_force_N, run.packets_per_s)
                      << std::flush;
          }
          }
        }
      }
    }
  }
  if (opt.json) printJson({{"glyph", opt.glyph}, {"seed", opt.seed}, {"rows", rows}});
}

void addStationOptions(CLI::App& cmd, MentorOptions& opt) {
  cmd.add_option("--key", opt.key, "Shared key file (`hattr device keygen --out FILE`)")->required();
  cmd.add_option("--device", opt.device, "This station's device URI (see `hattr devices`)")->capture_default_str();
  cmd.add_option("--hand", opt.hand, "A profile a simulated hand writes on a simulated pen, from when the link is up");
  cmd.add_option("--record", opt.record, "Write this station's haptic profile here (kept on failure, marked failed)");
  cmd.add_option("--record-dir", opt.record_dir, "Write each session's haptic profile to DIR/session-NNN.csv");
  cmd.add_option("--seconds", opt.seconds, "Record this long once linked (default: the hand script's length, or until "
                                           "interrupted)")
      ->check(CLI::Range(0.0, 36000.0));
  cmd.add_option("--wait", opt.wait_s, "Wait this long for the other station [s]")->check(CLI::Range(0.1, 3600.0))->capture_default_str();
  cmd.add_option("--deadband", opt.deadband, "Perceptual deadband: send a PEER only when velocity or force changed by "
                                             "more than this fraction (0: every tick; 0.1 is typical)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd.add_flag("--no-passivity", opt.no_passivity, "Turn the passivity observer/controller off (bilateral; for experiments)");
  cmd.add_flag("--force", opt.force, "Replace the --record file if it exists");
  cmd.add_flag("--json", opt.json, "Print a JSON summary: samples, packets, lost, link_faults, drops, energy, rtt_ms, failure");
}

}  // namespace

void registerMentorCommands(CLI::App& app) {
  auto* mentor = app.add_subcommand("mentor", "Live mentoring: an expert's station leads a trainee's over the network "
                                              "(docs/mentoring.md)");
  mentor->require_subcommand(1);

  auto lead_opt = std::make_shared<MentorOptions>();
  auto* lead = mentor->add_subcommand("lead", "The expert's station: listen for one trainee and share the pen");
  lead->add_option("--listen", lead_opt->address, "HOST:PORT to listen on (port 0: any free port, printed)")->required();
  lead->add_option("--sessions", lead_opt->sessions,
                   "Serve this many sessions one after another, waiting for each follower without limit (0: until "
                   "interrupted; a study's live mentor: each mentored trial is a session)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  addStationOptions(*lead, *lead_opt);
  lead->callback([lead_opt] { runStation(*lead_opt, net::MentorRole::kLeader); });

  auto follow_opt = std::make_shared<MentorOptions>();
  auto* follow = mentor->add_subcommand("follow", "The trainee's station: connect to the expert's and be coupled");
  follow->add_option("--connect", follow_opt->address, "The leader's HOST:PORT")->required();
  follow->add_option("--coupling", follow_opt->coupling, "observe, position, force or bilateral")
      ->check(CLI::IsMember({"observe", "position", "force", "bilateral"}))
      ->capture_default_str();
  addStationOptions(*follow, *follow_opt);
  follow->callback([follow_opt] { runStation(*follow_opt, net::MentorRole::kFollower); });

  auto sim_opt = std::make_shared<SimulateOptions>();
  auto* simulate = mentor->add_subcommand(
      "simulate", "Two simulated stations on an emulated link, in simulated time: the simulated expert writes the "
                  "glyph, a lagging trainee is coupled; tracking error, force error and the couplings' energy per "
                  "coupling × round trip × loss, with the passivity method on and off");
  simulate->add_option("--couplings", sim_opt->couplings, "Comma-separated couplings")->capture_default_str();
  simulate->add_option("--rtt-ms", sim_opt->rtt_ms, "Comma-separated round trips [ms]")->capture_default_str();
  simulate->add_option("--loss-percent", sim_opt->loss_percent, "Comma-separated loss rates [%]")->capture_default_str();
  simulate->add_option("--passivity", sim_opt->passivity, "on, off or both (off rows for bilateral only)")
      ->check(CLI::IsMember({"on", "off", "both"}))
      ->capture_default_str();
  simulate->add_option("--deadband", sim_opt->deadband,
                       "Comma-separated perceptual deadbands (Weber fractions; 0: a packet every tick)")
      ->capture_default_str();
  simulate->add_option("--seconds", sim_opt->seconds, "Recorded time per run (default: the glyph's length + 0.3 s)")
      ->check(CLI::Range(0.1, 600.0));
  simulate->add_option("--glyph", sim_opt->glyph, "The glyph the expert writes: a file, a built-in name or the character")->capture_default_str();
  simulate->add_option("--seed", sim_opt->seed, "Link emulator seed")->capture_default_str();
  simulate->add_option("--expert-device", sim_opt->expert_device, "The expert's simulated pen and hand (sim:// keys)")
      ->capture_default_str();
  simulate->add_option("--trainee-device", sim_opt->trainee_device,
                       "The trainee's simulated pen and hand (default: a compliant grip, 80 N/m)")
      ->capture_default_str();
  simulate->add_flag("--json", sim_opt->json, "Print JSON: rows of coupling, rtt_ms, loss_percent, passivity, "
                                              "tracking_rms_mm, force_rms_N, energy_generated_J, dissipated_J, ...");
  simulate->callback([sim_opt] { runSimulate(*sim_opt); });
}

}  // namespace hattr::cli
