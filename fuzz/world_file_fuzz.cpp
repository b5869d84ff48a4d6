// Fuzzes the world-file reader: any input either becomes a world configuration whose every
// number is finite, or is refused with hattr::InputError. Nothing else.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "hattr/core/error.hpp"
#include "hattr/render/world_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  hattr::render::WorldConfig world;
  try {
    world = hattr::render::parseWorldConfig(text, "fuzz.json", "");
  } catch (const hattr::InputError&) {
    return 0;
  }
  const auto& p = world.paper;
  for (const double v : {p.contact.stiffness_N_per_m, p.contact.damping_N_s_per_m, p.tangential_stiffness_N_per_m,
                         p.friction.static_coefficient, p.friction.dynamic_coefficient, p.texture.sigma,
                         p.texture.correlation_length_m}) {
    if (!std::isfinite(v)) __builtin_trap();
  }
  return 0;
}
