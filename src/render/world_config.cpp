#include "hattr/render/world_config.hpp"

#include "hattr/core/text_file.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"

namespace hattr::render {
namespace {

using nlohmann::json;

/// Reads the keys of one JSON object section, each checked against its range.
class Section {
 public:
  Section(const json& root, const char* name, std::string_view source) : source_(source), name_(name) {
    const auto found = root.find(name);
    if (found == root.end()) return;
    HATTR_THROW_UNLESS(found->is_object(), "{}: key {}: expected an object, got {}", source, name, jsonExcerpt(*found));
    object_ = &*found;
  }
  void number(const char* key, double& value, double lo, double hi) {
    known_.push_back(key);
    const json* v = find(key);
    if (!v) return;
    HATTR_THROW_UNLESS(v->is_number() && std::isfinite(v->get<double>()) && v->get<double>() >= lo && v->get<double>() <= hi,
                       "{}: key {}.{}: expected a number in [{}, {}], got {}", source_, name_, key, lo, hi, jsonExcerpt(*v));
    value = v->get<double>();
  }
  void integer(const char* key, std::uint64_t& value, std::uint64_t hi) {
    known_.push_back(key);
    const json* v = find(key);
    if (!v) return;
    HATTR_THROW_UNLESS(v->is_number_unsigned() && v->get<std::uint64_t>() <= hi,
                       "{}: key {}.{}: expected an integer in [0, {}], got {}", source_, name_, key, hi, jsonExcerpt(*v));
    value = v->get<std::uint64_t>();
  }
  void text(const char* key, std::string& value) {
    known_.push_back(key);
    const json* v = find(key);
    if (!v) return;
    HATTR_THROW_UNLESS(v->is_string(), "{}: key {}.{}: expected a string, got {}", source_, name_, key, jsonExcerpt(*v));
    value = v->get<std::string>();
  }
  /// Every key present must be one of those read.
  void finish() const {
    if (!object_) return;
    for (const auto& item : object_->items()) {
      if (std::find(known_.begin(), known_.end(), item.key()) != known_.end()) continue;
      std::string keys;
      for (const auto& k : known_) keys += (keys.empty() ? "" : ", ") + k;
      throw InputError(fmt::format("{}: unknown key \"{}.{}\": expected one of {}", source_, name_, item.key(), keys));
    }
  }

 private:
  const json* find(const char* key) const {
    if (!object_) return nullptr;
    const auto it = object_->find(key);
    return it == object_->end() ? nullptr : &*it;
  }
  std::string_view source_;
  const char* name_;
  const json* object_ = nullptr;
  std::vector<std::string> known_;
};

WorldConfig parseWorldObject(const json& root, std::string_view source, const std::filesystem::path& base_dir);

}  // namespace

WorldConfig parseWorldConfig(std::string_view json_text, std::string_view source, const std::filesystem::path& base_dir) {
  return readingJson(source, [&] { return parseWorldObject(parseJsonObject(json_text, source), source, base_dir); });
}

namespace {

WorldConfig parseWorldObject(const json& root, std::string_view source, const std::filesystem::path& base_dir) {
  for (const auto& item : root.items()) {
    static const std::vector<std::string> kTop{"paper", "friction", "texture", "relief", "writing_angle_deg"};
    HATTR_THROW_UNLESS(std::find(kTop.begin(), kTop.end(), item.key()) != kTop.end(),
                       "{}: unknown key \"{}\": expected one of paper, friction, texture, relief, writing_angle_deg",
                       source, item.key());
  }

  WorldConfig config;
  PaperParams& p = config.paper;
  Section paper(root, "paper", source);
  paper.number("stiffness_N_per_m", p.contact.stiffness_N_per_m, 1.0, 1e6);
  paper.number("damping_N_s_per_m", p.contact.damping_N_s_per_m, 0.0, 1e4);
  paper.number("tangential_stiffness_N_per_m", p.tangential_stiffness_N_per_m, 1.0, 1e6);
  paper.number("thickness_m", p.thickness_m, 1e-4, 0.05);
  paper.finish();

  Section friction(root, "friction", source);
  friction.number("static", p.friction.static_coefficient, 0.0, 2.0);
  friction.number("dynamic", p.friction.dynamic_coefficient, 0.0, 2.0);
  friction.finish();
  HATTR_THROW_UNLESS(p.friction.dynamic_coefficient <= p.friction.static_coefficient,
                     "{}: key friction.dynamic: expected a number in [0, friction.static = {}], got {}", source,
                     p.friction.static_coefficient, p.friction.dynamic_coefficient);

  Section texture(root, "texture", source);
  texture.number("sigma", p.texture.sigma, 0.0, 1.0);
  texture.number("correlation_length_m", p.texture.correlation_length_m, 1e-6, 0.1);
  texture.integer("seed", p.texture.seed, ~0ULL);
  texture.finish();

  ReliefConfig& r = config.relief;
  Section relief(root, "relief", source);
  std::string kind = "grain";
  std::string file;
  double vertices = r.vertices;
  relief.text("kind", kind);
  relief.number("size_m", r.size_m, 1e-3, 10.0);
  relief.number("vertices", vertices, 2.0, 4096.0);
  relief.number("amplitude_m", r.amplitude_m, 0.0, 0.01);
  relief.number("correlation_length_m", r.correlation_length_m, 1e-6, 0.1);
  relief.integer("seed", r.seed, ~0ULL);
  relief.text("file", file);
  relief.number("height_scale_m", r.height_scale_m, -0.01, 0.01);
  relief.finish();
  HATTR_THROW_UNLESS(kind == "flat" || kind == "grain" || kind == "pgm",
                     "{}: key relief.kind: expected one of flat, grain, pgm, got \"{}\"", source, kind);
  HATTR_THROW_UNLESS(vertices == std::floor(vertices), "{}: key relief.vertices: expected an integer, got {}", source,
                     vertices);
  r.kind = kind == "flat" ? ReliefConfig::Kind::kFlat : kind == "pgm" ? ReliefConfig::Kind::kPgm : ReliefConfig::Kind::kGrain;
  r.vertices = static_cast<int>(vertices);
  HATTR_THROW_UNLESS(r.kind != ReliefConfig::Kind::kPgm || !file.empty(), "{}: key relief.file: required when kind is pgm",
                     source);
  if (!file.empty()) r.file = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : base_dir / file;
  std::error_code ec;
  HATTR_THROW_UNLESS(r.kind != ReliefConfig::Kind::kPgm || std::filesystem::is_regular_file(r.file, ec),
                     "{}: key relief.file: file \"{}\" not found", source, r.file.string());

  if (const auto angle = root.find("writing_angle_deg"); angle != root.end()) {
    HATTR_THROW_UNLESS(angle->is_number() && angle->get<double>() >= 10.0 && angle->get<double>() <= 90.0,
                       "{}: key writing_angle_deg: expected a number in [10, 90], got {}", source, jsonExcerpt(*angle));
    p.writing_angle_rad = units::degreesToRadians(angle->get<double>());
  }
  return config;
}

}  // namespace

WorldConfig loadWorldConfig(const std::filesystem::path& file) {
  return parseWorldConfig(readTextFile(file), file.string(), file.parent_path());
}

std::string defaultWorldConfigJson() {
  const WorldConfig c;
  const PaperParams& p = c.paper;
  const json j = {
      {"paper",
       {{"stiffness_N_per_m", p.contact.stiffness_N_per_m},
        {"damping_N_s_per_m", p.contact.damping_N_s_per_m},
        {"tangential_stiffness_N_per_m", p.tangential_stiffness_N_per_m},
        {"thickness_m", p.thickness_m}}},
      {"friction", {{"static", p.friction.static_coefficient}, {"dynamic", p.friction.dynamic_coefficient}}},
      {"texture",
       {{"sigma", p.texture.sigma}, {"correlation_length_m", p.texture.correlation_length_m}, {"seed", p.texture.seed}}},
      {"relief",
       {{"kind", "grain"},
        {"size_m", c.relief.size_m},
        {"vertices", c.relief.vertices},
        {"amplitude_m", c.relief.amplitude_m},
        {"correlation_length_m", c.relief.correlation_length_m},
        {"seed", c.relief.seed}}},
      {"writing_angle_deg", std::round(units::radiansToDegrees(p.writing_angle_rad) * 1e9) / 1e9},
  };
  return j.dump(2);
}

HeightField buildRelief(const ReliefConfig& relief) {
  switch (relief.kind) {
    case ReliefConfig::Kind::kFlat: return {};
    case ReliefConfig::Kind::kGrain:
      return HeightField::paperGrain(relief.size_m, relief.vertices, relief.amplitude_m, relief.correlation_length_m,
                                     relief.seed);
    case ReliefConfig::Kind::kPgm: return HeightField::fromPgm(relief.file, relief.size_m, relief.height_scale_m);
  }
  return {};
}

}  // namespace hattr::render
