#pragma once
/// The paper/world configuration file (JSON): every rendering parameter with its unit in
/// its key name and a documented default (docs/rendering.md). Bad values are errors naming
/// the key, the allowed range and the value found.
///
///   {"paper":    {"stiffness_N_per_m": 600, "damping_N_s_per_m": 0.1, "tangential_stiffness_N_per_m": 500,
///                 "thickness_m": 0.003},
///    "friction": {"static": 0.30, "dynamic": 0.20},
///    "texture":  {"sigma": 0.03, "correlation_length_m": 0.0005, "seed": 1},
///    "relief":   {"kind": "grain", "size_m": 0.16, "vertices": 512, "amplitude_m": 1e-5,
///                 "correlation_length_m": 0.0005, "seed": 2},
///    "writing_angle_deg": 60}

#include <filesystem>
#include <string>
#include <string_view>

#include "hattr/render/paper_renderer.hpp"

namespace hattr::render {

struct ReliefConfig {
  enum class Kind { kFlat, kGrain, kPgm };
  Kind kind = Kind::kGrain;
  double size_m = 0.16;                 ///< side of the square the relief covers, centred on the origin
  int vertices = 512;                   ///< grain: vertices per side
  double amplitude_m = 1e-5;            ///< grain: standard deviation of the height
  double correlation_length_m = 5e-4;   ///< grain: ℓ
  std::uint64_t seed = 2;               ///< grain
  std::filesystem::path file;           ///< pgm: the image (relative to the config file)
  double height_scale_m = 5e-4;         ///< pgm: height of white
};

struct WorldConfig {
  PaperParams paper;
  ReliefConfig relief;
};

/// Parses a configuration; absent keys keep their defaults. `base_dir` resolves relative
/// PGM paths. Throws InputError for unknown keys, wrong types and out-of-range values.
WorldConfig parseWorldConfig(std::string_view json_text, std::string_view source_name,
                             const std::filesystem::path& base_dir = {});
WorldConfig loadWorldConfig(const std::filesystem::path& file);
/// The configuration with every default, as JSON (`hattr world defaults`).
std::string defaultWorldConfigJson();

/// The height field a relief configuration describes.
HeightField buildRelief(const ReliefConfig& relief);

}  // namespace hattr::render
