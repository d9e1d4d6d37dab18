// Tone curves for the PNG preview: how linear radiance (after --exposure) becomes display
// values in [0, 1] before the sRGB transfer curve. The EXR is never tone mapped.
#pragma once

#include <optional>
#include <string>

namespace lf {

enum class ToneCurve {
    // Values above 1 clip to white: the preview lightfarm always wrote.
    kClamp,
    // Krzysztof Narkowicz's fit of the ACES filmic curve (RRT + sRGB ODT, "ACES Filmic Tone
    // Mapping Curve", 2015): x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14) per channel. The
    // curve most real-time engines ship, one rational function with no parameters to tune: 0
    // stays 0, it is monotone, a slight toe darkens the shadows, and the shoulder rolls
    // highlights off, reaching white only at x = 7.24 (so 1 maps to 0.80).
    kFilmic,
};

// "clamp", "filmic"
const char* ToneCurveName(ToneCurve curve);
std::optional<ToneCurve> ToneCurveFromName(const std::string& name);

// Linear radiance to a display value: kClamp leaves it as it is (the sRGB encoder clamps),
// kFilmic maps [0, inf) into [0, 1]. Negative values and NaN give 0, +inf gives white.
float ApplyToneCurve(ToneCurve curve, float linear);

}  // namespace lf
