// The SVC2004 protocol on a library: draws, the distances they need (each pair once, per
// channel, in batches), scores, error rates, identification and the week's claim.

#include "hattr/library/evaluation.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <unordered_map>

#include <fmt/format.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/library/profile_template.hpp"

namespace hattr::library {

// ---- Error rates -------------------------------------------------------------------------------

std::pair<double, double> errorRatesAt(const std::vector<double>& genuine, const std::vector<double>& impostor,
                                       double threshold) {
  const auto above = std::count_if(genuine.begin(), genuine.end(), [&](double s) { return s > threshold; });
  const auto below = std::count_if(impostor.begin(), impostor.end(), [&](double s) { return s <= threshold; });
  return {static_cast<double>(below) / static_cast<double>(impostor.size()),
          static_cast<double>(above) / static_cast<double>(genuine.size())};
}

namespace {

/// FAR and FRR at every score as a threshold, thresholds ascending (a merge of both sorted sides).
struct Sweep {
  std::vector<double> thresholds, far, frr;
};

Sweep sweep(std::vector<double> genuine, std::vector<double> impostor) {
  HATTR_THROW_UNLESS(!genuine.empty() && !impostor.empty(),
                     "error rates: {} genuine and {} impostor scores; expected at least one of each", genuine.size(),
                     impostor.size());
  std::sort(genuine.begin(), genuine.end());
  std::sort(impostor.begin(), impostor.end());
  std::vector<double> all(genuine);
  all.insert(all.end(), impostor.begin(), impostor.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  Sweep s;
  const double ng = static_cast<double>(genuine.size());
  const double ni = static_cast<double>(impostor.size());
  std::size_t g = 0, i = 0;  // scores <= threshold on each side
  for (const double t : all) {
    while (g < genuine.size() && genuine[g] <= t) ++g;
    while (i < impostor.size() && impostor[i] <= t) ++i;
    s.thresholds.push_back(t);
    s.far.push_back(static_cast<double>(i) / ni);
    s.frr.push_back(static_cast<double>(genuine.size() - g) / ng);
  }
  return s;
}

}  // namespace

ErrorRates equalErrorRate(std::vector<double> genuine, std::vector<double> impostor) {
  ErrorRates r;
  r.genuine = genuine.size();
  r.impostor = impostor.size();
  const Sweep s = sweep(std::move(genuine), std::move(impostor));
  std::size_t best = 0;
  for (std::size_t k = 1; k < s.thresholds.size(); ++k) {
    if (std::abs(s.far[k] - s.frr[k]) < std::abs(s.far[best] - s.frr[best])) best = k;
  }
  r.eer = 0.5 * (s.far[best] + s.frr[best]);
  r.eer_threshold = s.thresholds[best];
  return r;
}

std::vector<std::pair<double, double>> detCurve(std::vector<double> genuine, std::vector<double> impostor) {
  const Sweep s = sweep(std::move(genuine), std::move(impostor));
  std::vector<std::pair<double, double>> out;
  for (std::size_t k = 0; k < s.thresholds.size(); ++k) out.emplace_back(s.far[k], s.frr[k]);
  return out;
}

// ---- The protocol's writers ---------------------------------------------------------------------

ProtocolOptions svc2004Protocol(const ProfileLibrary& library) {
  ProtocolOptions o;
  const auto persons = library.persons(o.skill);
  const std::set<std::string> have(persons.begin(), persons.end());
  for (int w = 1; w <= 40; ++w) {
    const std::string name = fmt::format("U{}", w);
    HATTR_THROW_UNLESS(have.count(name) == 1,
                       "{}: no {} profiles of writer {}; the svc2004 protocol needs writers U1-U40 as `hattr library "
                       "import svc2004` labels them",
                       library.location(), o.skill, name);
    (w <= 20 ? o.development : o.evaluation).push_back(name);
  }
  return o;
}

namespace {

/// One profile of the protocol, with its features.
struct Item {
  LibraryEntry entry;
  FeatureSeries features;
};

/// A writer's profiles by role, as indices into the items (in the library's order).
struct Writer {
  std::vector<std::size_t> first, second, imitations;
};

/// One enrolment and what is tested against it.
struct Draw {
  std::string split;
  std::string person;
  int run = 0;
  std::vector<std::size_t> references;
  std::vector<std::pair<std::size_t, std::string>> queries;  // item, kind
};

/// Per-channel DTW costs of item pairs, each pair once (ordered low, high), computed in batches.
class PairDistances {
 public:
  PairDistances(const std::vector<Item>& items, const FeatureOptions& options, unsigned threads)
      : items_(items), options_(options), threads_(threads) {}
  void want(std::size_t a, std::size_t b) {
    const auto key = keyOf(a, b);
    if (!costs_.count(key) && pending_.insert(key).second) order_.push_back(key);
  }
  /// Every pair asked for, every channel both have.
  void compute() {
    analysis::DtwOptions o;
    o.band_fraction = options_.band_fraction;
    for (const auto key : order_) costs_[key].fill(std::numeric_limits<double>::quiet_NaN());
    for (std::size_t c = 0; c < kFeatureChannels; ++c) {
      std::vector<std::span<const double>> a, b;
      std::vector<std::uint64_t> keys;
      for (const auto key : order_) {
        const auto& x = items_[key >> 32].features.channels[c];
        const auto& y = items_[key & 0xffffffffu].features.channels[c];
        if (x.empty() || y.empty()) continue;
        a.emplace_back(x);
        b.emplace_back(y);
        keys.push_back(key);
      }
      if (keys.empty()) continue;
      const auto d = analysis::dtwBatch(std::span<const std::span<const double>>(a),
                                        std::span<const std::span<const double>>(b), o, threads_);
      for (std::size_t k = 0; k < keys.size(); ++k) costs_[keys[k]][c] = d[k];
      computed_ += keys.size();
    }
    pending_.clear();
    order_.clear();
  }
  /// The feature distance over a set, as featureDistance defines it.
  [[nodiscard]] double distance(std::size_t a, std::size_t b, FeatureSet set) const {
    const auto& costs = costs_.at(keyOf(a, b));
    double sum = 0.0;
    for (const FeatureChannel c : set.channels()) sum += costs[static_cast<std::size_t>(c)];
    return sum / static_cast<double>(options_.length) +
           timingDistance(items_[a].features, items_[b].features, set, options_);
  }
  [[nodiscard]] std::size_t computed() const { return computed_; }

 private:
  static std::uint64_t keyOf(std::size_t a, std::size_t b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint64_t>(std::max(a, b));
  }
  const std::vector<Item>& items_;
  FeatureOptions options_;
  unsigned threads_;
  std::unordered_map<std::uint64_t, std::array<double, kFeatureChannels>> costs_;
  std::set<std::uint64_t> pending_;
  std::vector<std::uint64_t> order_;
  std::size_t computed_ = 0;
};

/// A generator for one (writer, run) draw: the same for a seed whatever else is drawn.
std::mt19937_64 drawGenerator(std::uint64_t seed, const std::string& person, int run, std::string_view split) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(std::hash<std::string>{}(person)), static_cast<std::uint32_t>(run),
                    static_cast<std::uint32_t>(split.size())};
  return std::mt19937_64(seq);
}

/// The protocol's draws for a split's writers.
std::vector<Draw> drawsOf(const std::string& split, const std::vector<std::string>& writers,
                          const std::map<std::string, Writer>& roles, const ProtocolOptions& o) {
  std::vector<Draw> draws;
  for (const std::string& w : writers) {
    const Writer& me = roles.at(w);
    for (int run = 0; run < o.runs; ++run) {
      std::mt19937_64 rng = drawGenerator(o.seed, w, run, split);
      Draw d{split, w, run, me.first, {}};
      std::shuffle(d.references.begin(), d.references.end(), rng);
      d.references.resize(static_cast<std::size_t>(o.enrolled));
      for (const auto i : me.second) d.queries.emplace_back(i, "genuine");
      for (const auto i : me.imitations) d.queries.emplace_back(i, "skilled");
      std::vector<std::string> others;
      for (const auto& v : writers) {
        if (v != w) others.push_back(v);
      }
      std::shuffle(others.begin(), others.end(), rng);
      others.resize(std::min(others.size(), static_cast<std::size_t>(o.random_forgers)));
      for (const auto& v : others) {
        const Writer& them = roles.at(v);
        std::vector<std::size_t> genuine(them.first);
        genuine.insert(genuine.end(), them.second.begin(), them.second.end());
        d.queries.emplace_back(genuine[std::uniform_int_distribution<std::size_t>(0, genuine.size() - 1)(rng)], "random");
      }
      draws.push_back(std::move(d));
    }
  }
  return draws;
}

void checkOptions(const ProtocolOptions& o) {
  checkFeatureOptions(o.features);
  HATTR_THROW_UNLESS(o.runs >= 1, "runs: expected at least 1, got {}", o.runs);
  HATTR_THROW_UNLESS(o.enrolled >= 2, "enrolled: expected at least 2 profiles (a spread needs two), got {}", o.enrolled);
  HATTR_THROW_UNLESS(o.random_forgers >= 1, "random forgers: expected at least 1, got {}", o.random_forgers);
  HATTR_THROW_UNLESS(!o.sets.empty(), "feature sets: expected at least one");
  HATTR_THROW_UNLESS(!o.development.empty() && !o.evaluation.empty(),
                     "writers: expected development and evaluation writers");
  HATTR_THROW_UNLESS(o.threads >= 1, "threads: expected at least 1, got {}", o.threads);
}

/// The template against single recordings on the evaluation writers (TemplateResult).
TemplateResult measureTemplates(const std::vector<Item>& items, const std::map<std::string, Writer>& roles,
                                const std::vector<Draw>& draws, const ProtocolOptions& o,
                                const ProfileLibrary& library) {
  const FeatureSet set{FeatureSet::kShape | FeatureSet::kForce};
  TemplateResult t;
  std::size_t better = 0;
  for (const std::string& w : o.evaluation) {
    const auto draw = std::find_if(draws.begin(), draws.end(),
                                   [&](const Draw& d) { return d.split == "evaluation" && d.person == w && d.run == 0; });
    std::vector<HapticProfile> recordings;
    for (const auto r : draw->references) recordings.push_back(library.profile(items[r].entry.id));
    const auto made = buildTemplate(recordings, {.subject = w, .skill = o.skill});
    const FeatureSeries averaged = extractFeatures(made.profile, o.features, fmt::format("the template of {}", w));
    double to_template = 0.0, to_single = 0.0;
    const Writer& me = roles.at(w);
    for (const auto held_out : me.second) {
      to_template += featureDistance(averaged, items[held_out].features, set, o.features);
      for (const auto r : draw->references) to_single += featureDistance(items[r].features, items[held_out].features, set, o.features);
    }
    to_template /= static_cast<double>(me.second.size());
    to_single /= static_cast<double>(me.second.size() * draw->references.size());
    t.template_distance += to_template / static_cast<double>(o.evaluation.size());
    t.single_distance += to_single / static_cast<double>(o.evaluation.size());
    better += to_template < to_single ? 1 : 0;
  }
  t.writers = o.evaluation.size();
  t.writers_better = static_cast<double>(better) / static_cast<double>(t.writers);
  return t;
}

/// The protocol's profiles, by writer and role, with every feature they have.
struct Corpus {
  std::vector<Item> items;
  std::map<std::string, Writer> roles;
};

Corpus loadCorpus(const ProfileLibrary& library, const ProtocolOptions& o, const std::vector<std::string>& writers) {
  const std::set<std::string> wanted(writers.begin(), writers.end());
  Corpus c;
  for (auto& e : library.list({.skill = o.skill})) {
    if (!wanted.count(e.labels.person)) continue;
    Writer& w = c.roles[e.labels.person];
    const std::size_t i = c.items.size();
    if (e.labels.authenticity == Authenticity::kImitation) {
      w.imitations.push_back(i);
    } else if (e.labels.session == "1") {
      w.first.push_back(i);
    } else if (e.labels.session == "2") {
      w.second.push_back(i);
    } else {
      continue;
    }
    const std::string where = fmt::format("{}: entry {}", library.location(), e.labels.key);
    FeatureSeries f = extractFeatures(library.profile(e.id), o.features, where);
    for (const FeatureSet set : o.sets) requireChannels(f, set, where);
    c.items.push_back({std::move(e), std::move(f)});
  }
  // Entries come ordered by key; draws index them in id order, so a draw does not depend on names.
  for (auto& [name, w] : c.roles) {
    for (auto* list : {&w.first, &w.second, &w.imitations}) {
      std::sort(list->begin(), list->end(),
                [&](std::size_t a, std::size_t b) { return c.items[a].entry.id < c.items[b].entry.id; });
    }
  }
  for (const auto& name : writers) {
    const auto it = c.roles.find(name);
    const std::size_t first = it == c.roles.end() ? 0 : it->second.first.size();
    const std::size_t second = it == c.roles.end() ? 0 : it->second.second.size();
    const std::size_t imitations = it == c.roles.end() ? 0 : it->second.imitations.size();
    HATTR_THROW_UNLESS(first >= static_cast<std::size_t>(o.enrolled) && second > 0 && imitations > 0,
                       "{}: writer {} needs at least {} genuine {} profiles of session 1, one of session 2 and one "
                       "imitation; has {}, {} and {}",
                       library.location(), name, o.enrolled, o.skill, first, second, imitations);
  }
  return c;
}

/// Every pair of profiles the draws, identification and the claim compare, computed once.
void requestPairs(PairDistances& distances, const std::vector<Draw>& draws, const Corpus& c,
                  const std::vector<std::string>& all_writers, const std::vector<std::string>& evaluation) {
  for (const Draw& d : draws) {
    for (std::size_t a = 0; a < d.references.size(); ++a) {
      for (std::size_t b = a + 1; b < d.references.size(); ++b) distances.want(d.references[a], d.references[b]);
      for (const auto& [q, kind] : d.queries) distances.want(d.references[a], q);
    }
  }
  // Identification: every second-session profile against every first-session one (the "all"
  // split holds both others).
  for (const auto& w : all_writers) {
    for (const auto& v : all_writers) {
      for (const auto a : c.roles.at(v).first) {
        for (const auto b : c.roles.at(w).second) distances.want(a, b);
      }
    }
  }
  // The claim's blocks on the evaluation writers: within each session.
  for (const auto& w : evaluation) {
    for (const auto* session : {&c.roles.at(w).first, &c.roles.at(w).second}) {
      for (std::size_t a = 0; a < session->size(); ++a) {
        for (std::size_t b = a + 1; b < session->size(); ++b) distances.want((*session)[a], (*session)[b]);
      }
    }
  }
  distances.compute();
}

/// Scores by split and kind ("genuine", "skilled", "random") of one feature set; each score a row.
using SplitScores = std::map<std::string, std::map<std::string, std::vector<double>>>;

SplitScores scoreDraws(const std::vector<Draw>& draws, const Corpus& c, const PairDistances& distances, FeatureSet set,
                       ScoreRule rule, std::vector<ScoreRow>& rows) {
  SplitScores by_split;
  for (const Draw& d : draws) {
    std::vector<double> within;
    for (std::size_t a = 0; a < d.references.size(); ++a) {
      for (std::size_t b = a + 1; b < d.references.size(); ++b) {
        within.push_back(distances.distance(d.references[a], d.references[b], set));
      }
    }
    const double spread = std::accumulate(within.begin(), within.end(), 0.0) / static_cast<double>(within.size());
    HATTR_THROW_UNLESS(spread > 0.0, "writer {}: run {}: the enrolled profiles are identical in {}", d.person, d.run,
                       set.name());
    for (const auto& [q, kind] : d.queries) {
      std::vector<double> to_refs;
      for (const auto r : d.references) to_refs.push_back(distances.distance(r, q, set));
      const double score = verificationScore(to_refs, spread, rule);
      by_split[d.split][kind].push_back(score);
      rows.push_back({d.split, set.name(), d.person, d.run, c.items[q].entry.labels.key, kind, score});
    }
  }
  return by_split;
}

/// Closed-set identification on a split: (rank-1 hits, rank-5 hits, probes), persons ranked by
/// their nearest first-session profile, ties by name (identifyBruteForce's order).
std::array<std::size_t, 3> identificationHits(const std::vector<std::string>& writers, const Corpus& c,
                                              const PairDistances& distances, FeatureSet set) {
  std::array<std::size_t, 3> hits{};
  for (const auto& w : writers) {
    for (const auto i : c.roles.at(w).second) {
      std::vector<std::pair<double, std::string>> nearest;
      for (const auto& v : writers) {
        double best = std::numeric_limits<double>::infinity();
        for (const auto g : c.roles.at(v).first) best = std::min(best, distances.distance(g, i, set));
        nearest.emplace_back(best, v);
      }
      std::sort(nearest.begin(), nearest.end());
      const auto at = std::find_if(nearest.begin(), nearest.end(), [&](const auto& p) { return p.second == w; });
      const auto rank = static_cast<std::size_t>(at - nearest.begin());
      hits[0] += rank < 1 ? 1 : 0;
      hits[1] += rank < 5 ? 1 : 0;
      ++hits[2];
    }
  }
  return hits;
}

/// One split's error rates (the a-priori thresholds given), DET curves and identification.
SplitResult splitResult(const std::string& name, const std::vector<std::string>& writers, SplitScores& scores,
                        const ErrorRates& dev_skilled, const ErrorRates& dev_random, const Corpus& c,
                        const PairDistances& distances, FeatureSet set) {
  auto& s = scores[name];
  SplitResult r{name, writers.size()};
  r.skilled = equalErrorRate(s["genuine"], s["skilled"]);
  r.random = equalErrorRate(s["genuine"], s["random"]);
  r.skilled.prior_threshold = dev_skilled.eer_threshold;
  r.random.prior_threshold = dev_random.eer_threshold;
  std::tie(r.skilled.far, r.skilled.frr) = errorRatesAt(s["genuine"], s["skilled"], r.skilled.prior_threshold);
  std::tie(r.random.far, r.random.frr) = errorRatesAt(s["genuine"], s["random"], r.random.prior_threshold);
  r.det_skilled = detCurve(s["genuine"], s["skilled"]);
  r.det_random = detCurve(s["genuine"], s["random"]);
  const auto hits = identificationHits(writers, c, distances, set);
  r.probes = hits[2];
  r.rank1 = static_cast<double>(hits[0]) / static_cast<double>(r.probes);
  r.rank5 = static_cast<double>(hits[1]) / static_cast<double>(r.probes);
  return r;
}

/// The week's claim on the evaluation writers (ClaimResult).
ClaimResult claimOf(const std::vector<std::string>& evaluation, const Corpus& c, const PairDistances& distances,
                    FeatureSet set) {
  ClaimResult claim{set.name()};
  double within = 0, across = 0, between = 0;
  std::size_t n_within = 0, n_across = 0, n_between = 0, nearer = 0;
  for (const auto& w : evaluation) {
    const Writer& me = c.roles.at(w);
    for (const auto* session : {&me.first, &me.second}) {
      for (std::size_t a = 0; a < session->size(); ++a) {
        for (std::size_t b = a + 1; b < session->size(); ++b, ++n_within) {
          within += distances.distance((*session)[a], (*session)[b], set);
        }
      }
    }
    double nearest_other = std::numeric_limits<double>::infinity();
    double self = 0.0;
    for (const auto& v : evaluation) {
      double block = 0.0;
      std::size_t n = 0;
      for (const auto a : c.roles.at(v).first) {
        for (const auto b : me.second) block += distances.distance(a, b, set), ++n;
      }
      if (v == w) {
        across += block, n_across += n, self = block / static_cast<double>(n);
      } else {
        between += block, n_between += n;
        nearest_other = std::min(nearest_other, block / static_cast<double>(n));
      }
    }
    nearer += self < nearest_other ? 1 : 0;
  }
  claim.within_session = within / static_cast<double>(n_within);
  claim.across_sessions = across / static_cast<double>(n_across);
  claim.between_writers = between / static_cast<double>(n_between);
  claim.writers_nearer_themselves = static_cast<double>(nearer) / static_cast<double>(evaluation.size());
  return claim;
}

}  // namespace

EvaluationResult evaluate(const ProfileLibrary& library, const ProtocolOptions& o) {
  checkOptions(o);
  const auto started = std::chrono::steady_clock::now();
  EvaluationResult result;
  result.options = o;
  std::vector<std::string> all_writers(o.development);
  all_writers.insert(all_writers.end(), o.evaluation.begin(), o.evaluation.end());
  const Corpus c = loadCorpus(library, o, all_writers);

  // The draws of each split, and every distance they need, computed once.
  const std::vector<std::pair<std::string, const std::vector<std::string>*>> splits = {
      {"development", &o.development}, {"evaluation", &o.evaluation}, {"all", &all_writers}};
  std::vector<Draw> draws;
  for (const auto& [name, writers] : splits) {
    auto d = drawsOf(name, *writers, c.roles, o);
    draws.insert(draws.end(), std::make_move_iterator(d.begin()), std::make_move_iterator(d.end()));
  }
  PairDistances distances(c.items, o.features, o.threads);
  requestPairs(distances, draws, c, all_writers, o.evaluation);

  // Each feature set: scores, error rates (a-priori thresholds from the development writers),
  // identification, the claim.
  for (const FeatureSet set : o.sets) {
    SplitScores scores = scoreDraws(draws, c, distances, set, o.rule, result.scores);
    const ErrorRates dev_skilled = equalErrorRate(scores["development"]["genuine"], scores["development"]["skilled"]);
    const ErrorRates dev_random = equalErrorRate(scores["development"]["genuine"], scores["development"]["random"]);
    SetResult sr{set, {}};
    for (const auto& [name, writers] : splits) {
      sr.splits.push_back(splitResult(name, *writers, scores, dev_skilled, dev_random, c, distances, set));
    }
    result.sets.push_back(std::move(sr));
    result.claim.push_back(claimOf(o.evaluation, c, distances, set));
  }
  result.templates = measureTemplates(c.items, c.roles, draws, o, library);
  result.week.person = o.evaluation.front();
  for (const auto i : c.roles.at(result.week.person).first) result.week.first.push_back(c.items[i].features[FeatureChannel::kForce]);
  for (const auto i : c.roles.at(result.week.person).second) result.week.second.push_back(c.items[i].features[FeatureChannel::kForce]);
  result.distances = distances.computed();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

}  // namespace hattr::library
