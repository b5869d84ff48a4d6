// A study's design: groups, sessions and blocks read from a study file (or the paper's form
// turned into them), checked as a whole, written back, and planned into trials.

#include <algorithm>
#include <random>
#include <set>

#include "hattr/session/study.hpp"
#include "study_problems.hpp"

namespace hattr::session {
namespace detail {
namespace {

using nlohmann::json;

/// The protocol keys that only the paper's form has (a design says its trials per block).
const std::set<std::string> kPaperProtocolKeys{"training_trials", "recall_trials", "training", "recall",
                                               "analyzed_recall_trials"};

bool isTestPhase(std::string_view phase) {
  return phase == kPhasePostTest || phase == kPhaseRetention || phase == kPhaseTransfer;
}

/// A list of strategy names (modes) into `out`; `where` names the key.
void readStrategyList(const json& list, const std::string& where, std::vector<guidance::TrainingMode>& out,
                      Problems& problems) {
  if (!list.is_array() || list.empty()) {
    problems.add(fmt::format("{}: expected a non-empty list such as [\"basic\", \"pcontrol\", \"alpha\"], got {}", where,
                             jsonExcerpt(list)));
    return;
  }
  std::set<guidance::TrainingMode> seen;
  for (const auto& m : list) {
    try {
      const auto mode = guidance::parseMode(m.is_string() ? m.get<std::string>() : jsonExcerpt(m));
      if (!seen.insert(mode).second) problems.add(fmt::format("{}: {} listed twice", where, jsonExcerpt(m)));
      out.push_back(mode);
    } catch (const InputError& e) {
      problems.add(fmt::format("{}: {}", where, e.what()));
    }
  }
}

/// A block's "strategy": absent or "none", "group" (position 1 of the subject's order),
/// {"order": k}, or a strategy's name.
StrategyRef readStrategyRef(const json& block, const std::string& where, Problems& problems) {
  StrategyRef ref;
  const auto it = block.find("strategy");
  if (it == block.end() || *it == "none") return ref;
  if (*it == "group") return {StrategyRef::Kind::kOrderPosition, guidance::TrainingMode::kBasic, 1};
  if (it->is_object()) {
    ref.kind = StrategyRef::Kind::kOrderPosition;
    if (it->size() != 1 || !it->contains("order")) {
      problems.add(fmt::format("{}strategy: expected {{\"order\": K}} (the K-th strategy of the subject's order), got {}",
                               where, jsonExcerpt(*it)));
    }
    readNumber(*it, "order", ref.position, 1, 64, where + "strategy.", problems);
    return ref;
  }
  try {
    ref.mode = guidance::parseMode(it->is_string() ? it->get<std::string>() : jsonExcerpt(*it));
    ref.kind = StrategyRef::Kind::kNamed;
  } catch (const InputError& e) {
    problems.add(fmt::format("{}strategy: expected \"none\", \"group\", {{\"order\": K}} or a strategy: {}", where,
                             e.what()));
  }
  return ref;
}

Block readBlock(const json& b, const std::string& where, const StudyDefinition& study, Problems& problems) {
  static const std::set<std::string> kBlockKeys{"phase", "skill", "strategy", "trials", "show_reference", "guidance",
                                                "rest_s"};
  Block block;
  block.skill = study.skill;
  block.rest_s = study.protocol.rest_s;
  if (!b.is_object()) {
    problems.add(fmt::format("{}: expected a block {{\"phase\", \"skill\", \"strategy\", \"trials\", ...}}, got {}",
                             where.substr(0, where.size() - 1), jsonExcerpt(b)));
    return block;
  }
  for (const auto& item : b.items()) {
    if (!kBlockKeys.contains(item.key())) {
      problems.add(fmt::format("{}{}: unknown key: expected phase, skill, strategy, trials, show_reference, guidance, "
                               "rest_s", where, textExcerpt(item.key())));
    }
  }
  const auto text = [&](const char* key, std::string& out) {
    if (const auto it = b.find(key); it != b.end()) {
      if (it->is_string() && !it->get<std::string>().empty()) out = it->get<std::string>();
      else problems.add(fmt::format("{}{}: expected a non-empty string, got {}", where, key, jsonExcerpt(*it)));
    }
  };
  text("phase", block.phase);
  text("skill", block.skill);
  if (!isSafeFileName(block.phase)) {  // it names files and CSV cells
    problems.add(fmt::format("{}phase: \"{}\": expected {}", where, textExcerpt(block.phase), kSafeFileNameRule));
  }
  if (!b.contains("trials")) problems.add(fmt::format("{}trials: missing (how many trials, at least 1)", where));
  readNumber(b, "trials", block.trials, 1, 1000, where, problems);
  readNumber(b, "rest_s", block.rest_s, 0.0, 3600.0, where, problems);
  block.strategy = readStrategyRef(b, where, problems);
  // What the trainee gets: by default the reference in training, and the strategy's force
  // wherever a block has one.
  block.view.show_reference = block.phase == kPhaseTraining;
  block.view.guidance = block.strategy.kind != StrategyRef::Kind::kNone;
  readBool(b, "show_reference", block.view.show_reference, where, problems);
  readBool(b, "guidance", block.view.guidance, where, problems);
  if (!study.experts.empty() && !study.experts.contains(block.skill)) {
    problems.add(fmt::format("{}skill: \"{}\" has no expert reference in experts", where, textExcerpt(block.skill)));
  }
  if (block.view.guidance && block.strategy.kind == StrategyRef::Kind::kNone) {
    problems.add(fmt::format("{}guidance: true, but the block names no strategy", where));
  }
  return block;
}

void readSessions(const json& root, StudyDefinition& study, Problems& problems) {
  const auto sessions = root.find("sessions");
  if (!sessions->is_array() || sessions->empty()) {
    problems.add(fmt::format("sessions: expected a non-empty list of {{\"day\": N, \"blocks\": [...]}}, got {}",
                             jsonExcerpt(*sessions)));
    return;
  }
  for (std::size_t s = 0; s < sessions->size(); ++s) {
    const json& session = (*sessions)[s];
    const std::string where = fmt::format("sessions[{}].", s + 1);
    ScheduledSession scheduled;
    if (!session.is_object()) {
      problems.add(fmt::format("sessions[{}]: expected {{\"day\": N, \"blocks\": [...]}}, got {}", s + 1,
                               jsonExcerpt(session)));
      continue;
    }
    for (const auto& item : session.items()) {
      if (item.key() != "day" && item.key() != "blocks") {
        problems.add(fmt::format("{}{}: unknown key: expected day, blocks", where, textExcerpt(item.key())));
      }
    }
    readNumber(session, "day", scheduled.day, 0, 3650, where, problems);
    const auto blocks = session.find("blocks");
    if (blocks == session.end() || !blocks->is_array() || blocks->empty()) {
      problems.add(fmt::format("{}blocks: expected a non-empty list of blocks", where));
    } else {
      for (std::size_t b = 0; b < blocks->size(); ++b) {
        scheduled.blocks.push_back(readBlock((*blocks)[b], fmt::format("{}blocks[{}].", where, b + 1), study, problems));
      }
    }
    study.schedule.push_back(std::move(scheduled));
  }
}

void readGroups(const json& root, StudyDefinition& study, Problems& problems) {
  const auto groups = root.find("groups");
  if (!groups->is_array() || groups->empty()) {
    problems.add(fmt::format("groups: expected a non-empty list of {{\"name\", \"strategies\", \"subjects\"}}, got {}",
                             jsonExcerpt(*groups)));
    return;
  }
  std::set<std::string> names;
  for (std::size_t g = 0; g < groups->size(); ++g) {
    const json& object = (*groups)[g];
    const std::string where = fmt::format("groups[{}].", g + 1);
    if (!object.is_object()) {
      problems.add(fmt::format("groups[{}]: expected {{\"name\", \"strategies\", \"subjects\"}}, got {}", g + 1,
                               jsonExcerpt(object)));
      continue;
    }
    for (const auto& item : object.items()) {
      if (item.key() != "name" && item.key() != "strategies" && item.key() != "subjects") {
        problems.add(fmt::format("{}{}: unknown key: expected name, strategies, subjects", where, textExcerpt(item.key())));
      }
    }
    Group group;
    if (const auto n = object.find("name"); n != object.end() && n->is_string() && isSafeFileName(n->get<std::string>())) {
      group.name = n->get<std::string>();
      if (!names.insert(group.name).second) problems.add(fmt::format("{}name: \"{}\" used twice", where, group.name));
    } else {
      problems.add(fmt::format("{}name: expected {}, got {}", where, kSafeFileNameRule,
                               n == object.end() ? std::string("nothing") : jsonExcerpt(*n)));
    }
    if (const auto s = object.find("strategies"); s != object.end()) {
      readStrategyList(*s, where + "strategies", group.strategies, problems);
    } else {
      group.strategies = {guidance::TrainingMode::kBasic};  // a control group: no strategy of its own
    }
    if (const auto s = object.find("subjects"); s != object.end()) {
      auto subjects = readSubjects(*s, where + "subjects", group.name, study.subjects.size(), problems,
                                   group.name.empty() ? std::string("S") : group.name);
      study.subjects.insert(study.subjects.end(), subjects.begin(), subjects.end());
    } else {
      problems.add(fmt::format("{}subjects: missing: a group without subjects", where));
    }
    study.groups.push_back(std::move(group));
  }
}

/// The paper's form: modes, protocol and subjects (applyPaperForm).
void readPaperForm(const json& root, StudyDefinition& study, Problems& problems) {
  study.modes.clear();
  if (const auto it = root.find("modes"); it != root.end()) {
    readStrategyList(*it, "modes", study.modes, problems);
  } else {
    study.modes = {guidance::TrainingMode::kBasic, guidance::TrainingMode::kPositionControl,
                   guidance::TrainingMode::kForceControl};
  }
  if (study.protocol.training_trials + study.protocol.recall_trials == 0) {
    problems.add("protocol: zero trials per mode (training_trials + recall_trials)");
  }
  const auto subjects = root.find("subjects");
  if (subjects == root.end()) {
    problems.add("subjects: missing (a list of {\"id\": ...} or {\"count\": N})");
  } else {
    study.subjects = readSubjects(*subjects, "subjects", std::string(kWithinSubjectsGroup), 0, problems);
  }
  applyPaperForm(study);
}

/// The design as a whole: strategies that exist for every group, tests after training, days
/// that never go back.
void checkDesign(StudyDefinition& study, Problems& problems) {
  std::size_t fewest = 64;
  for (const Group& g : study.groups) fewest = std::min(fewest, g.strategies.size());
  bool trained = false;
  int last_day = 0;
  for (std::size_t s = 0; s < study.schedule.size(); ++s) {
    const ScheduledSession& session = study.schedule[s];
    if (session.day < last_day) {
      problems.add(fmt::format("sessions[{}].day: {} goes back before sessions[{}]'s day {}", s + 1, session.day, s,
                               last_day));
    }
    last_day = std::max(last_day, session.day);
    for (std::size_t b = 0; b < session.blocks.size(); ++b) {
      const Block& block = session.blocks[b];
      const std::string where = fmt::format("sessions[{}].blocks[{}]", s + 1, b + 1);
      if (block.strategy.kind == StrategyRef::Kind::kOrderPosition &&
          static_cast<std::size_t>(block.strategy.position) > fewest) {
        problems.add(fmt::format("{}.strategy: position {} of the subject's order, but a group has only {} "
                                 "strateg{}", where, block.strategy.position, fewest, fewest == 1 ? "y" : "ies"));
      }
      // The expert's station mentors with the study's expert: a mentored strategy on another skill cannot be.
      const bool mentored =
          (block.strategy.kind == StrategyRef::Kind::kNamed && guidance::isMentored(block.strategy.mode)) ||
          (block.strategy.kind == StrategyRef::Kind::kOrderPosition &&
           std::any_of(study.groups.begin(), study.groups.end(), [](const Group& g) {
             return std::any_of(g.strategies.begin(), g.strategies.end(), guidance::isMentored);
           }));
      if (mentored && block.view.guidance && block.skill != study.skill) {
        problems.add(fmt::format("{}.skill: \"{}\" with a mentored strategy: the expert's station mentors the "
                                 "study's skill \"{}\" only", where, block.skill, study.skill));
      }
      if (isTestPhase(block.phase) && !trained) {
        problems.add(fmt::format("{}.phase: a {} block before any training block", where, block.phase));
      }
      trained = trained || block.phase == kPhaseTraining;
    }
  }
}

/// Every strategy the study uses, first use first: the groups' then the named blocks'.
std::vector<guidance::TrainingMode> strategiesUsed(const StudyDefinition& study) {
  std::vector<guidance::TrainingMode> used;
  const auto note = [&used](guidance::TrainingMode m) {
    if (std::find(used.begin(), used.end(), m) == used.end()) used.push_back(m);
  };
  for (const Group& g : study.groups) std::for_each(g.strategies.begin(), g.strategies.end(), note);
  for (const auto& session : study.schedule) {
    for (const Block& b : session.blocks) {
      if (b.strategy.kind == StrategyRef::Kind::kNamed) note(b.strategy.mode);
    }
  }
  return used;
}

json strategyRefJson(const StrategyRef& ref) {
  switch (ref.kind) {
    case StrategyRef::Kind::kNone: return "none";
    case StrategyRef::Kind::kNamed: return std::string(guidance::modeName(ref.mode));
    case StrategyRef::Kind::kOrderPosition: return json{{"order", ref.position}};
  }
  return "none";
}

json subjectJson(const SubjectSpec& s) {
  return {{"id", s.id}, {"participant", s.participant}, {"seed", s.seed}, {"options", s.options}};
}

}  // namespace

std::vector<SubjectSpec> readSubjects(const json& subjects, const std::string& where, const std::string& group,
                                      std::uint64_t first_seed, Problems& problems, const std::string& default_prefix) {
  std::vector<SubjectSpec> out;
  if (subjects.is_object()) {
    static const std::set<std::string> kSubjectKeys{"count", "prefix", "participant", "options"};
    for (const auto& item : subjects.items()) {
      if (!kSubjectKeys.contains(item.key())) {
        problems.add(fmt::format("{}: unknown key \"{}\": expected count, prefix, participant or options", where,
                                 textExcerpt(item.key())));
      }
    }
    if (!subjects.contains("count")) problems.add(fmt::format("{}.count: missing (how many subjects)", where));
    int count = 0;
    readNumber(subjects, "count", count, 1, 10'000, where + ".", problems);
    const std::string prefix = subjects.value("prefix", default_prefix);
    const std::string participant = subjects.value("participant", std::string("simulated"));
    for (int i = 1; i <= count; ++i) {
      out.push_back({fmt::format("{}{:02}", prefix, i), participant, first_seed + static_cast<std::uint64_t>(i),
                     subjects.value("options", json::object()), group});
    }
    return out;
  }
  if (!subjects.is_array() || subjects.empty()) {
    problems.add(fmt::format("{}: expected a non-empty list or {{\"count\": N}}, got {}", where, jsonExcerpt(subjects)));
    return out;
  }
  for (std::size_t i = 0; i < subjects.size(); ++i) {
    const json& s = subjects[i];
    if (!s.is_object() || !s.contains("id") || !s["id"].is_string() || s["id"].get<std::string>().empty()) {
      problems.add(fmt::format("{}[{}]: expected an object with a non-empty \"id\"", where, i));
      continue;
    }
    SubjectSpec spec{s["id"].get<std::string>(), s.value("participant", std::string("simulated")),
                     first_seed + static_cast<std::uint64_t>(i + 1), s.value("options", json::object()), group};
    readNumber(s, "seed", spec.seed, 0, 9.0e15, fmt::format("{}[{}].", where, i), problems);
    const bool repeated = std::any_of(out.begin(), out.end(), [&](const SubjectSpec& o) { return o.id == spec.id; });
    if (repeated) problems.add(fmt::format("{}[{}]: id \"{}\" used twice", where, i, spec.id));
    out.push_back(std::move(spec));
  }
  return out;
}

void readDesign(const json& root, StudyDefinition& study, Problems& problems) {
  const bool has_groups = root.contains("groups"), has_sessions = root.contains("sessions");
  study.paper_form = !has_groups && !has_sessions;
  if (study.paper_form) {
    readPaperForm(root, study, problems);
  } else {
    // A design: groups and sessions together, and none of the paper's form.
    if (!has_groups) problems.add("groups: missing: a design with sessions names its groups (one group is fine)");
    if (!has_sessions) problems.add("sessions: missing: a design with groups names its sessions and their blocks");
    for (const char* key : {"modes", "subjects"}) {
      if (root.contains(key)) {
        problems.add(fmt::format("{}: not with groups and sessions: each group names its strategies and subjects", key));
      }
    }
    if (const auto p = root.find("protocol"); p != root.end() && p->is_object()) {
      for (const auto& item : p->items()) {
        if (kPaperProtocolKeys.contains(item.key())) {
          problems.add(fmt::format("protocol.{}: only in the paper's form (modes + protocol): in a design each block "
                                   "says its trials, phase and view", item.key()));
        }
      }
    }
    if (has_groups) readGroups(root, study, problems);
    if (has_sessions) readSessions(root, study, problems);
  }
  // An id in two groups (one group's repeats are named where they are listed).
  std::map<std::string, std::string> group_of;
  for (const SubjectSpec& s : study.subjects) {
    const auto [first, fresh] = group_of.emplace(s.id, s.group);
    if (!fresh && first->second != s.group) {
      problems.add(fmt::format("subject id \"{}\" is in groups {} and {}", textExcerpt(s.id), first->second, s.group));
    }
  }
  checkDesign(study, problems);
  study.modes = strategiesUsed(study);
}

void writeDesign(const StudyDefinition& study, json& root) {
  json groups = json::array();
  for (const Group& g : study.groups) {
    json strategies = json::array(), subjects = json::array();
    for (const auto m : g.strategies) strategies.push_back(std::string(guidance::modeName(m)));
    for (const SubjectSpec& s : study.subjects) {
      if (s.group == g.name) subjects.push_back(subjectJson(s));
    }
    groups.push_back({{"name", g.name}, {"strategies", strategies}, {"subjects", subjects}});
  }
  json sessions = json::array();
  for (const ScheduledSession& s : study.schedule) {
    json blocks = json::array();
    for (const Block& b : s.blocks) {
      blocks.push_back({{"phase", b.phase}, {"skill", b.skill}, {"strategy", strategyRefJson(b.strategy)},
                        {"trials", b.trials}, {"show_reference", b.view.show_reference}, {"guidance", b.view.guidance},
                        {"rest_s", b.rest_s}});
    }
    sessions.push_back({{"day", s.day}, {"blocks", blocks}});
  }
  root["groups"] = groups;
  root["sessions"] = sessions;
  root.erase("modes");
  root.erase("subjects");
  for (const auto& key : kPaperProtocolKeys) root["protocol"].erase(key);
}

}  // namespace detail

void applyPaperForm(StudyDefinition& study) {
  const Protocol& p = study.protocol;
  ScheduledSession session;
  for (int position = 1; position <= static_cast<int>(study.modes.size()); ++position) {
    const StrategyRef ref{StrategyRef::Kind::kOrderPosition, guidance::TrainingMode::kBasic, position};
    if (p.training_trials > 0) {
      session.blocks.push_back({std::string(kPhaseTraining), study.skill, ref, p.training_trials, p.training, p.rest_s});
    }
    if (p.recall_trials > 0) {
      session.blocks.push_back({std::string(kPhaseRecall), study.skill, ref, p.recall_trials, p.recall, p.rest_s});
    }
  }
  study.schedule = {session};
  study.groups = {Group{std::string(kWithinSubjectsGroup), study.modes}};
  for (SubjectSpec& s : study.subjects) s.group = kWithinSubjectsGroup;
  study.paper_form = true;
}

bool isPaperDesign(const StudyDefinition& study) { return study.paper_form; }

std::vector<std::vector<guidance::TrainingMode>> modeOrders(const StudyDefinition& study) {
  // Williams design for n strategies: first row 0, 1, n-1, 2, n-2, ...; row r adds r (mod n).
  // For odd n the mirrored square follows, so every strategy precedes every other equally often.
  const auto williams = [](const std::vector<guidance::TrainingMode>& modes) {
    const std::size_t n = modes.size();
    std::vector<std::size_t> first;
    for (std::size_t k = 0, lo = 1, hi = n - 1; k < n; ++k) first.push_back(k == 0 ? 0 : (k % 2 == 1 ? lo++ : hi--));
    std::vector<std::vector<guidance::TrainingMode>> rows;
    for (std::size_t r = 0; r < n; ++r) {
      std::vector<guidance::TrainingMode> row;
      for (const std::size_t c : first) row.push_back(modes[(c + r) % n]);
      rows.push_back(row);
    }
    if (n % 2 == 1) {
      for (std::size_t r = 0; r < n; ++r) rows.emplace_back(rows[r].rbegin(), rows[r].rend());
    }
    return rows;
  };
  std::vector<std::vector<guidance::TrainingMode>> orders;
  std::mt19937_64 rng(study.order_seed);
  std::map<std::string, std::size_t> position_in_group;
  for (const SubjectSpec& subject : study.subjects) {
    const auto group = std::find_if(study.groups.begin(), study.groups.end(),
                                    [&](const Group& g) { return g.name == subject.group; });
    HATTR_DEMAND(group != study.groups.end(), "subject {} is in no group of the study", subject.id);
    const std::size_t position = position_in_group[subject.group]++;
    switch (study.order) {
      case OrderKind::kLatinSquare: {
        const auto rows = williams(group->strategies);
        orders.push_back(rows[position % rows.size()]);
        break;
      }
      case OrderKind::kFixed: orders.push_back(group->strategies); break;
      case OrderKind::kRandom: {
        auto order = group->strategies;
        for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);  // portable shuffle
        orders.push_back(order);
        break;
      }
    }
  }
  return orders;
}

std::vector<TrialPlan> planTrials(const StudyDefinition& study, const SubjectSpec& subject,
                                  const std::vector<guidance::TrainingMode>& order) {
  std::vector<TrialPlan> plan;
  for (std::size_t s = 0; s < study.schedule.size(); ++s) {
    const ScheduledSession& session = study.schedule[s];
    for (std::size_t b = 0; b < session.blocks.size(); ++b) {
      const Block& block = session.blocks[b];
      guidance::TrainingMode mode = guidance::TrainingMode::kBasic;
      if (block.strategy.kind == StrategyRef::Kind::kNamed) mode = block.strategy.mode;
      if (block.strategy.kind == StrategyRef::Kind::kOrderPosition) {
        HATTR_DEMAND(static_cast<std::size_t>(block.strategy.position) <= order.size(),
                     "subject {}: the order has no position {}", subject.id, block.strategy.position);
        mode = order[static_cast<std::size_t>(block.strategy.position - 1)];
      }
      for (int i = 1; i <= block.trials; ++i) {
        plan.push_back({subject.id, static_cast<int>(plan.size()), mode, block.phase, i, block.view, block.skill,
                        subject.group, static_cast<int>(s), session.day, static_cast<int>(b)});
      }
    }
  }
  return plan;
}

const Block& blockOf(const StudyDefinition& study, const TrialPlan& plan) {
  HATTR_DEMAND(plan.session >= 0 && static_cast<std::size_t>(plan.session) < study.schedule.size() &&
                   plan.block >= 0 &&
                   static_cast<std::size_t>(plan.block) < study.schedule[static_cast<std::size_t>(plan.session)].blocks.size(),
               "trial {} of subject {}: session {} block {} is not in the study's schedule", plan.sequence, plan.subject,
               plan.session, plan.block);
  return study.schedule[static_cast<std::size_t>(plan.session)].blocks[static_cast<std::size_t>(plan.block)];
}

}  // namespace hattr::session
