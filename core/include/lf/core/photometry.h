// Photometric units (candela, lumen, lux, nits) against the radiometric ones the renderer keeps.
#pragma once

#include "lf/core/rgb.h"

namespace lf {

// 683 lm/W, the luminous efficacy at 555 nm: KHR_lights_punctual's and Blender's conversion.
inline constexpr double kLumensPerWatt = 683;

// The photometric value of a radiometric RGB: lux of an irradiance (W m^-2), nits (cd/m^2) of a
// radiance (W m^-2 sr^-1), through Rec.709's luminance as the rest of the product uses.
inline float Photometric(const Rgb& radiometric) {
    return float(kLumensPerWatt) * radiometric.Luminance();
}

}  // namespace lf
