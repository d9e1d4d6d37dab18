#include "lf/core/tone_map.h"

#include <cmath>

namespace lf {

const char* ToneCurveName(ToneCurve curve) {
    return curve == ToneCurve::kFilmic ? "filmic" : "clamp";
}

std::optional<ToneCurve> ToneCurveFromName(const std::string& name) {
    if (name == "clamp") return ToneCurve::kClamp;
    if (name == "filmic") return ToneCurve::kFilmic;
    return std::nullopt;
}

float ApplyToneCurve(ToneCurve curve, float linear) {
    if (curve == ToneCurve::kClamp) return linear;
    if (!(linear > 0)) return 0;  // negative, zero or NaN
    if (std::isinf(linear)) return 1;
    const float x = linear;
    const float y = x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f);
    return std::fmin(y, 1.0f);
}

}  // namespace lf
