// Photometric units (candela, lumen, lux, nits) against the radiometric ones the renderer keeps.
#pragma once

namespace lf {

// 683 lm/W, the luminous efficacy at 555 nm: KHR_lights_punctual's and Blender's conversion.
inline constexpr double kLumensPerWatt = 683;

}  // namespace lf
