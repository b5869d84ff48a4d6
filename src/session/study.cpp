#include "sql_connection.hpp"
#include "hattr/session/study.hpp"

#include "hattr/core/text_file.hpp"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <numeric>
#include <random>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/trial_physics.hpp"
#include "study_problems.hpp"

namespace hattr::session {
namespace {

using detail::Problems;
using detail::readBool;
using detail::readNumber;
using nlohmann::json;

/// protocol.analyzed_recall_trials: distinct trial numbers within recall_trials (checked
/// after recall_trials is read).
void readAnalyzedRecall(const json& protocol, Protocol& p, Problems& problems) {
  const auto it = protocol.find("analyzed_recall_trials");
  if (it == protocol.end()) return;
  const std::string expected =
      fmt::format("protocol.analyzed_recall_trials: expected a list of distinct recall trial numbers in [1, {}]",
                  p.recall_trials);
  if (!it->is_array() || it->empty()) {
    problems.add(fmt::format("{}, got {}", expected, jsonExcerpt(*it)));
    return;
  }
  std::set<int> seen;
  for (const auto& v : *it) {
    if (!v.is_number_integer() || v.get<int>() < 1 || v.get<int>() > p.recall_trials || !seen.insert(v.get<int>()).second) {
      problems.add(fmt::format("{}, got {}", expected, jsonExcerpt(v)));
      return;
    }
  }
  p.analyzed_recall_trials.assign(seen.begin(), seen.end());
}

void readPhaseView(const json& object, const char* key, PhaseView& view, Problems& problems) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  if (!it->is_object()) {
    problems.add(fmt::format("protocol.{}: expected an object {{\"show_reference\": bool, \"guidance\": bool}}", key));
    return;
  }
  for (const auto& item : it->items()) {
    bool* target = item.key() == "show_reference" ? &view.show_reference : item.key() == "guidance" ? &view.guidance : nullptr;
    if (!target) {
      problems.add(fmt::format("protocol.{}: unknown key \"{}\": expected show_reference, guidance", key, item.key()));
    } else if (!item.value().is_boolean()) {
      problems.add(fmt::format("protocol.{}.{}: expected true or false, got {}", key, item.key(), jsonExcerpt(item.value())));
    } else {
      *target = item.value().get<bool>();
    }
  }
}

/// protocol.trial_end {"pen_up_s": s, "max_s": s}; absent (or null) with tail_s present: the
/// old fixed window (Protocol::fixed_window).
void readTrialEnd(const json& protocol, Protocol& p, Problems& problems) {
  const auto it = protocol.find("trial_end");
  if (it == protocol.end() || it->is_null()) {
    p.fixed_window = protocol.contains("tail_s");
    return;
  }
  if (!it->is_object()) {
    problems.add(fmt::format("protocol.trial_end: expected an object {{\"pen_up_s\": seconds, \"max_s\": seconds}}, got {}",
                             jsonExcerpt(*it)));
    return;
  }
  for (const auto& item : it->items()) {
    if (item.key() != "pen_up_s" && item.key() != "max_s") {
      problems.add(fmt::format("protocol.trial_end: unknown key \"{}\": expected pen_up_s, max_s", item.key()));
    }
  }
  readNumber(*it, "pen_up_s", p.trial_end.pen_up_s, 0.05, 60.0, "protocol.trial_end.", problems);
  readNumber(*it, "max_s", p.trial_end.max_s, 0.0, 3600.0, "protocol.trial_end.", problems);
  if (p.trial_end.max_s > 0.0 && p.trial_end.max_s <= p.trial_end.pen_up_s) {
    problems.add(fmt::format("protocol.trial_end.max_s: expected 0 (3 × the expert's duration) or more than pen_up_s = {}, got {}",
                             p.trial_end.pen_up_s, p.trial_end.max_s));
  }
}

/// The mentor block {"expert": "simulated" | "live", ...} (docs/studies.md). Live needs where
/// the expert's station listens and the key file (relative to the study file).
void readMentor(const json& root, const std::filesystem::path& base_dir, bool check_files, StudyDefinition& study,
                Problems& problems) {
  const auto it = root.find("mentor");
  if (it == root.end()) return;
  if (!it->is_object()) {
    problems.add(fmt::format("mentor: expected an object {{\"expert\": \"simulated\" | \"live\", ...}}, got {}", jsonExcerpt(*it)));
    return;
  }
  static const std::set<std::string> kMentorKeys{"expert",   "connect",      "key",        "round_trip_ms", "jitter_ms",
                                                 "loss_percent", "expert_device", "passivity", "deadband"};
  for (const auto& item : it->items()) {
    if (!kMentorKeys.contains(item.key())) {
      problems.add(fmt::format("mentor: unknown key \"{}\": expected one of expert, connect, key, round_trip_ms, "
                               "jitter_ms, loss_percent, expert_device, passivity, deadband", item.key()));
    }
  }
  StudyMentor& m = study.mentor;
  const auto string_key = [&](const char* key, std::string& out) {
    if (const auto v = it->find(key); v != it->end() && !v->is_null()) {  // null: absent (as studyToJson writes it)
      if (v->is_string() && !v->get<std::string>().empty()) out = v->get<std::string>();
      else problems.add(fmt::format("mentor.{}: expected a non-empty string, got {}", key, jsonExcerpt(*v)));
    }
  };
  string_key("expert", m.expert);
  string_key("connect", m.connect);
  string_key("expert_device", m.expert_device);
  std::string key;
  string_key("key", key);
  double round_trip_ms = m.round_trip_s * 1e3, jitter_ms = m.jitter_s * 1e3, loss_percent = m.loss * 100.0;
  readNumber(*it, "round_trip_ms", round_trip_ms, 0.0, 2000.0, "mentor.", problems);
  readNumber(*it, "jitter_ms", jitter_ms, 0.0, 500.0, "mentor.", problems);
  readNumber(*it, "loss_percent", loss_percent, 0.0, 50.0, "mentor.", problems);
  readNumber(*it, "deadband", m.deadband, 0.0, 1.0, "mentor.", problems);
  m.round_trip_s = round_trip_ms * 1e-3;
  m.jitter_s = jitter_ms * 1e-3;
  m.loss = loss_percent * 1e-2;
  if (const auto v = it->find("passivity"); v != it->end()) {
    if (v->is_boolean()) m.passivity = v->get<bool>();
    else problems.add(fmt::format("mentor.passivity: expected true or false, got {}", jsonExcerpt(*v)));
  }

  // Who the expert is decides which keys are needed.
  if (m.expert == "live") {
    if (m.connect.empty()) problems.add("mentor.connect: a live expert needs HOST:PORT where `hattr mentor lead` listens");
    if (key.empty()) {
      problems.add("mentor.key: a live expert needs the key file both stations share (`hattr device keygen`)");
    } else {
      m.key = key;
      if (m.key.is_relative()) m.key = base_dir / m.key;
      if (check_files && !std::filesystem::is_regular_file(m.key)) {
        problems.add(fmt::format("mentor.key: key file \"{}\" not found", m.key.string()));
      }
    }
  } else if (m.expert != "simulated") {
    problems.add(fmt::format("mentor.expert: expected \"simulated\" or \"live\", got \"{}\"", m.expert));
  }
}

/// strategy_parameters: {"STRATEGY": {"PARAMETER": number or choice, ...}, ...}, each checked
/// against the catalog as it would be set.
void readStrategyParameters(const json& root, StudyDefinition& study, Problems& problems) {
  const auto it = root.find("strategy_parameters");
  if (it == root.end()) return;
  if (!it->is_object()) {
    problems.add(fmt::format("strategy_parameters: expected {{\"strategy\": {{\"parameter\": value, ...}}, ...}}, got {}",
                             jsonExcerpt(*it)));
    return;
  }
  for (const auto& strategy : it->items()) {
    guidance::TrainingMode mode{};
    try {
      mode = guidance::parseMode(strategy.key());
    } catch (const InputError& e) {
      problems.add(fmt::format("strategy_parameters: {}", e.what()));
      continue;
    }
    if (study.strategy_parameters.contains(mode)) {  // "Fading" and "fading": names in any case
      problems.add(fmt::format("strategy_parameters.{}: {} is given twice", strategy.key(), guidance::strategyName(mode)));
      continue;
    }
    if (!strategy.value().is_object()) {
      problems.add(fmt::format("strategy_parameters.{}: expected {{\"parameter\": value, ...}}, got {}", strategy.key(),
                               jsonExcerpt(strategy.value())));
      continue;
    }
    std::vector<guidance::StrategySetting> settings;
    for (const auto& parameter : strategy.value().items()) {
      const json& v = parameter.value();
      if (!v.is_number() && !v.is_string()) {
        problems.add(fmt::format("strategy_parameters.{}.{}: expected a number or a choice's name, got {}", strategy.key(),
                                 parameter.key(), jsonExcerpt(v)));
        continue;
      }
      // A number as its shortest exact text.
      settings.emplace_back(parameter.key(), v.is_string() ? v.get<std::string>() : fmt::format("{}", v.get<double>()));
    }
    try {
      guidance::GuidanceConfig check;
      guidance::setStrategyParameters(check, mode, settings);
    } catch (const InputError& e) {
      problems.add(fmt::format("strategy_parameters: {}", e.what()));
    }
    study.strategy_parameters[mode] = std::move(settings);
  }
}

StudyDefinition parseStudyObject(const json& root, std::string_view source, const std::filesystem::path& base_dir,
                                 bool check_files);

}  // namespace

StudyDefinition parseStudy(std::string_view json_text, std::string_view source, const std::filesystem::path& base_dir,
                           bool check_files) {
  return readingJson(source, [&] { return parseStudyObject(parseJsonObject(json_text, source), source, base_dir, check_files); });
}

namespace {

/// A file name's extension in lower case (".csv").
std::string lowerExtension(std::string_view value) {
  std::string extension = std::filesystem::path(value).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extension;
}

/// The top-level keys: every one known, and the format this build reads.
void checkTopLevelKeys(const json& root, Problems& problems) {
  static const std::set<std::string> kKeys{"format",   "name",    "skill",    "experts",  "modes",
                                           "protocol", "order",   "device",   "world",    "rate_hz",
                                           "indexing", "subjects", "mentor",  "storage",  "groups",
                                           "sessions", "strategy_parameters"};
  for (const auto& item : root.items()) {
    if (!kKeys.contains(item.key())) problems.add(fmt::format("unknown key \"{}\"", item.key()));
  }
  if (const auto f = root.find("format"); f != root.end() && *f != "hattr-study/1") {
    problems.add(fmt::format("format: expected \"hattr-study/1\", got {}", jsonExcerpt(*f)));
  }
}

/// name and skill (required) and device, each a non-empty string.
void readNames(const json& root, StudyDefinition& study, Problems& problems) {
  const auto text = [&](const char* key, std::string& out, bool required) {
    const auto it = root.find(key);
    if (it == root.end()) {
      if (required) problems.add(fmt::format("{}: missing (a string)", key));
    } else if (!it->is_string() || it->get<std::string>().empty()) {
      problems.add(fmt::format("{}: expected a non-empty string, got {}", key, jsonExcerpt(*it)));
    } else {
      out = it->get<std::string>();
    }
  };
  text("name", study.name, true);
  text("skill", study.skill, true);
  text("device", study.device, false);
}

/// experts {"SKILL": file, glyph file, built-in glyph's name or character, ...}, with one for
/// the study's skill (read first).
void readExperts(const json& root, const std::filesystem::path& base_dir, bool check_files, StudyDefinition& study,
                 Problems& problems) {
  if (const auto it = root.find("experts"); it == root.end() || !it->is_object() || it->empty()) {
    problems.add("experts: expected an object {\"skill\": \"expert.csv\", ...} with at least one entry");
  } else {
    for (const auto& item : it->items()) {
      if (!item.value().is_string()) {
        problems.add(fmt::format("experts.{}: expected a file, a built-in glyph's name or its character, got {}", item.key(),
                                 jsonExcerpt(item.value())));
        continue;
      }
      // A glyph file (.json, beside the study file), a built-in glyph's name or its character:
      // the simulated expert writing it (sim::recordNamedExperts). Else a profile file: an
      // existing one, or any value with a '/' or ending in .csv. A stored definition's files are
      // not looked at (the database holds the experts).
      const std::string value = item.value().get<std::string>();
      // A person's template in a profile library (library:PATH#PERSON/SKILL, the path beside
      // the study file): built when the study is made (sim::recordNamedExperts).
      if (value.rfind("library:", 0) == 0) {
        const auto hash = value.rfind('#');
        if (hash == std::string::npos || hash <= 8) {
          problems.add(fmt::format("experts.{}: \"{}\": expected library:PATH#PERSON/SKILL", item.key(), value));
          continue;
        }
        std::filesystem::path library = value.substr(8, hash - 8);
        if (library.is_relative() && !detail::isPostgresLocation(library.string())) {
          library = std::filesystem::absolute(base_dir / library);
        }
        study.named_experts[item.key()] = "library:" + library.string() + value.substr(hash);
        study.experts[item.key()] = study.named_experts[item.key()];
        continue;
      }
      std::filesystem::path file = value;
      if (file.is_relative()) file = base_dir / file;
      std::error_code unreadable;
      const bool existing = check_files && std::filesystem::is_regular_file(file, unreadable);
      const bool glyph_file = lowerExtension(value) == ".json";
      if (glyph_file || (!existing && value.find('/') == std::string::npos && lowerExtension(value) != ".csv")) {
        if (glyph_file && check_files && !existing) {
          problems.add(fmt::format("experts.{}: glyph file \"{}\" not found", item.key(), file.string()));
        }
        const std::filesystem::path named = glyph_file ? std::filesystem::absolute(file) : std::filesystem::path(value);
        study.named_experts[item.key()] = named.string();
        study.experts[item.key()] = named;
        continue;
      }
      if (check_files && !std::filesystem::is_regular_file(file)) {
        problems.add(fmt::format("experts.{}: expert file \"{}\" not found", item.key(), file.string()));
      }
      study.experts[item.key()] = file;
    }
    if (!study.skill.empty() && !study.experts.contains(study.skill)) {
      problems.add(fmt::format("skill \"{}\": no expert reference for it in experts", study.skill));
    }
  }
}

/// The protocol block {"training_trials", "recall_trials", "rest_s", ...} into study.protocol.
void readProtocol(const json& root, StudyDefinition& study, Problems& problems) {
  if (const auto it = root.find("protocol"); it != root.end()) {
    if (!it->is_object()) {
      problems.add("protocol: expected an object");
    } else {
      static const std::set<std::string> kProtocolKeys{"training_trials", "recall_trials", "rest_s",  "tail_s",
                                                       "training",        "recall",        "analyzed_recall_trials",
                                                       "disturbed_trials", "max_repeats",  "show_scores",
                                                       "trial_end"};
      for (const auto& item : it->items()) {
        if (!kProtocolKeys.contains(item.key())) problems.add(fmt::format("protocol: unknown key \"{}\"", item.key()));
      }
      Protocol& p = study.protocol;
      readNumber(*it, "training_trials", p.training_trials, 0, 1000, "protocol.", problems);
      readNumber(*it, "recall_trials", p.recall_trials, 0, 1000, "protocol.", problems);
      readNumber(*it, "rest_s", p.rest_s, 0.0, 3600.0, "protocol.", problems);
      readNumber(*it, "tail_s", p.tail_s, 0.0, 60.0, "protocol.", problems);
      readTrialEnd(*it, p, problems);
      readPhaseView(*it, "training", p.training, problems);
      readPhaseView(*it, "recall", p.recall, problems);
      readAnalyzedRecall(*it, p, problems);
      readNumber(*it, "max_repeats", p.max_repeats, 0, 10, "protocol.", problems);
      if (const auto d = it->find("disturbed_trials"); d != it->end()) {
        const std::string policy = d->is_string() ? d->get<std::string>() : jsonExcerpt(*d);
        if (policy == "repeat") p.disturbed = DisturbedPolicy::kRepeat;
        else if (policy == "flag") p.disturbed = DisturbedPolicy::kFlag;
        else if (policy == "exclude") p.disturbed = DisturbedPolicy::kExclude;
        else problems.add(fmt::format("protocol.disturbed_trials: expected \"repeat\", \"flag\" or \"exclude\", got {}", jsonExcerpt(*d)));
      }
      readBool(*it, "show_scores", p.show_scores, "protocol.", problems);
    }
  }
}

/// order {"kind", "seed"}, rate_hz, indexing and world.
void readOrderRateIndexingWorld(const json& root, StudyDefinition& study, Problems& problems) {
  if (const auto it = root.find("order"); it != root.end()) {
    const std::string kind = it->is_object() && it->contains("kind") && (*it)["kind"].is_string() ? (*it)["kind"].get<std::string>() : "";
    if (kind == "latin-square") study.order = OrderKind::kLatinSquare;
    else if (kind == "fixed") study.order = OrderKind::kFixed;
    else if (kind == "random") study.order = OrderKind::kRandom;
    else problems.add(fmt::format("order: expected {{\"kind\": \"latin-square\" | \"fixed\" | \"random\", \"seed\": N}}, got {}", jsonExcerpt(*it)));
    if (it->is_object()) readNumber(*it, "seed", study.order_seed, 0, 9.0e15, "order.", problems);
  }
  readNumber(root, "rate_hz", study.rate_hz, 1.0, 10'000.0, "", problems);
  if (const auto it = root.find("indexing"); it != root.end()) {
    try {
      study.indexing = guidance::parseIndexing(it->is_string() ? it->get<std::string>() : jsonExcerpt(*it));
    } catch (const InputError& e) {
      problems.add(e.what());
    }
  }
  if (const auto it = root.find("world"); it != root.end()) {
    if (!it->is_object()) problems.add("world: expected a world configuration object (docs/rendering.md)");
    else study.world = *it;
  }
}

/// storage {"resolution": ...}: how the samples are stored.
void readStorage(const json& root, StudyDefinition& study, Problems& problems) {
  if (const auto it = root.find("storage"); it != root.end()) {
    if (!it->is_object()) {
      problems.add(fmt::format("storage: expected {{\"resolution\": ...}}, got {}", jsonExcerpt(*it)));
    } else {
      for (const auto& item : it->items()) {
        if (item.key() != "resolution") problems.add(fmt::format("storage: unknown key \"{}\": expected resolution", item.key()));
      }
      if (const auto r = it->find("resolution"); r != it->end()) {
        try {
          study.resolution = io::parseResolution(r->dump(), "storage.resolution");
        } catch (const InputError& e) {
          problems.add(e.what());
        }
      }
    }
  }
}

/// The subjects' ids and the skills as file names, and each subject's participant kind.
void checkNamesAndParticipants(const StudyDefinition& study, bool check_files, Problems& problems) {
  // Subject ids and skills become file names (an export's trials/<id>/, experts/<skill>.csv):
  // a new study file's must be safe ones; a stored study keeps what it was created with (the
  // export's writer refuses only what would leave its folder).
  for (const auto& s : study.subjects) {
    if (check_files && !isSafeFileName(s.id)) {
      problems.add(fmt::format("subject id \"{}\": expected {}", textExcerpt(s.id), kSafeFileNameRule));
    }
  }
  for (const auto& [skill, file] : study.experts) {
    if (check_files && !isSafeFileName(skill)) {
      problems.add(fmt::format("experts: skill \"{}\": expected {}", textExcerpt(skill), kSafeFileNameRule));
    }
  }
  for (const auto& s : study.subjects) {
    if (s.participant != "simulated" && s.participant != "script" && s.participant != "person") {
      problems.add(fmt::format("subject {}: participant \"{}\": expected simulated, script or person", s.id, s.participant));
    }
  }
}

/// A study definition from its JSON object, each section read by its own function above;
/// every problem found is reported at once.
StudyDefinition parseStudyObject(const json& root, std::string_view source, const std::filesystem::path& base_dir,
                                 bool check_files) {
  Problems problems(source);
  StudyDefinition study;
  checkTopLevelKeys(root, problems);

  // Name, skill, experts.
  readNames(root, study, problems);
  readExperts(root, base_dir, check_files, study, problems);

  // Protocol.
  readProtocol(root, study, problems);

  // Who mentors the mentored modes.
  readMentor(root, base_dir, check_files, study, problems);

  // Order, rate, indexing, world.
  readOrderRateIndexingWorld(root, study, problems);

  // How the samples are stored: lossless, or at a declared resolution.
  readStorage(root, study, problems);

  readStrategyParameters(root, study, problems);

  // Groups, subjects and the schedule (or the paper's modes, protocol and subjects).
  detail::readDesign(root, study, problems);

  // Subject ids and skills as file names; participants.
  checkNamesAndParticipants(study, check_files, problems);
  problems.throwIfAny();
  return study;
}

}  // namespace

bool checkExpertsRenderable(const StudyDefinition& study) {
  // A simulated pen's limits are known without opening it; any other device's when a trial opens it.
  const std::optional<DeviceLimits> declared = device::limitsWithoutOpening(study.device);
  if (!declared) return false;
  const DeviceLimits& limits = *declared;
  std::vector<std::string> refused;
  for (const auto& [skill, path] : study.experts) {
    const auto named = study.named_expert_profiles.find(skill);
    if (study.named_experts.contains(skill) && named == study.named_expert_profiles.end()) continue;  // not recorded yet
    const HapticProfile expert = named != study.named_expert_profiles.end() ? named->second : io::readProfileCsv(path);
    for (const std::string& problem : renderabilityProblems(expert, limits)) {
      refused.push_back(fmt::format("the expert of {} ({}) on {}: {}", skill, path.string(), study.device, problem));
    }
  }
  HATTR_THROW_UNLESS(refused.empty(), "{}", fmt::join(refused, "\n"));
  return true;
}

StudyDefinition loadStudy(const std::filesystem::path& file) {
  return parseStudy(readTextFile(file), file.string(), file.parent_path());
}

nlohmann::json studyToJson(const StudyDefinition& s) {
  json experts = json::object();
  for (const auto& [skill, file] : s.experts) experts[skill] = file.string();
  json modes = json::array();
  for (const auto m : s.modes) modes.push_back(std::string(guidance::modeName(m)));
  const auto view = [](const PhaseView& v) { return json{{"show_reference", v.show_reference}, {"guidance", v.guidance}}; };
  json subjects = json::array();
  for (const auto& sub : s.subjects) {
    subjects.push_back({{"id", sub.id}, {"participant", sub.participant}, {"seed", sub.seed}, {"options", sub.options}});
  }
  const char* order = s.order == OrderKind::kLatinSquare ? "latin-square" : s.order == OrderKind::kFixed ? "fixed" : "random";
  json root = {{"format", "hattr-study/1"},
          {"name", s.name},
          {"skill", s.skill},
          {"experts", experts},
          {"modes", modes},
          {"protocol",
           {{"training_trials", s.protocol.training_trials},
            {"recall_trials", s.protocol.recall_trials},
            {"rest_s", s.protocol.rest_s},
            {"tail_s", s.protocol.tail_s},
            {"trial_end", s.protocol.fixed_window ? json(nullptr)
                                                  : json{{"pen_up_s", s.protocol.trial_end.pen_up_s},
                                                         {"max_s", s.protocol.trial_end.max_s}}},
            {"training", view(s.protocol.training)},
            {"recall", view(s.protocol.recall)},
            {"analyzed_recall_trials", analyzedRecallTrials(s.protocol)},
            {"disturbed_trials", std::string(disturbedPolicyName(s.protocol.disturbed))},
            {"max_repeats", s.protocol.max_repeats},
            {"show_scores", s.protocol.show_scores}}},
          {"order", {{"kind", order}, {"seed", s.order_seed}}},
          {"device", s.device},
          {"world", s.world},
          {"rate_hz", s.rate_hz},
          {"indexing", std::string(guidance::indexingName(s.indexing))},
          {"storage", {{"resolution", json::parse(io::resolutionJson(s.resolution))}}},
          {"subjects", subjects},
          {"mentor",
           {{"expert", s.mentor.expert},
            {"connect", s.mentor.connect.empty() ? json(nullptr) : json(s.mentor.connect)},
            {"key", s.mentor.key.empty() ? json(nullptr) : json(s.mentor.key.string())},
            {"round_trip_ms", s.mentor.round_trip_s * 1e3},
            {"jitter_ms", s.mentor.jitter_s * 1e3},
            {"loss_percent", s.mentor.loss * 100.0},
            {"expert_device", s.mentor.expert_device},
            {"passivity", s.mentor.passivity},
            {"deadband", s.mentor.deadband}}}};
  // Only a study that sets strategy parameters says so (a stored definition stays as it was).
  if (!s.strategy_parameters.empty()) {
    json parameters = json::object();
    for (const auto& [mode, settings] : s.strategy_parameters) {
      json values = json::object();
      for (const auto& [name, value] : settings) {
        // A number as a number (its text is exact), a choice as its name.
        double number = 0.0;
        const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), number);
        const bool numeric = ec == std::errc() && end == value.data() + value.size();
        values[name] = numeric ? json(number) : json(value);
      }
      parameters[guidance::strategyName(mode)] = values;
    }
    root["strategy_parameters"] = parameters;
  }
  // A design is written as one; the paper's form stays as it was read (a stored definition
  // is compared byte for byte by `study push`).
  if (!s.paper_form) detail::writeDesign(s, root);
  return root;
}

std::string_view disturbedPolicyName(DisturbedPolicy policy) {
  switch (policy) {
    case DisturbedPolicy::kRepeat: return "repeat";
    case DisturbedPolicy::kFlag: return "flag";
    case DisturbedPolicy::kExclude: return "exclude";
  }
  return "?";
}

std::vector<int> analyzedRecallTrials(const Protocol& protocol) {
  if (!protocol.analyzed_recall_trials.empty()) return protocol.analyzed_recall_trials;
  std::vector<int> trials;
  for (int i = protocol.recall_trials >= 2 ? 2 : 1; i <= protocol.recall_trials; ++i) trials.push_back(i);
  return trials;
}


}  // namespace hattr::session
