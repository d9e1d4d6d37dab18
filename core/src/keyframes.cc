#include "lf/core/keyframes.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace lf {
namespace {

void Normalize4(std::span<double> q) {
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (norm > 0) {
        for (double& c : q) c /= norm;
    }
}

// The specification's slerp: along the shorter arc (b negated when the two differ by more than
// a half turn), a normalised lerp where the keys nearly coincide and sin(angle) vanishes.
void Slerp(const double* a, const double* b, double s, std::span<double> out) {
    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    const double sign = dot < 0 ? -1 : 1;
    dot *= sign;
    double wa = 1 - s, wb = s;
    if (dot < 0.9995) {
        const double angle = std::acos(dot), sine = std::sin(angle);
        wa = std::sin((1 - s) * angle) / sine;
        wb = std::sin(s * angle) / sine;
    }
    for (int c = 0; c < 4; ++c) out[size_t(c)] = wa * a[c] + wb * sign * b[c];
    Normalize4(out);
}

}  // namespace

absl::StatusOr<Interpolation> ParseInterpolation(const std::string& name,
                                                 const std::string& where) {
    if (name.empty() || name == "LINEAR") return Interpolation::kLinear;
    if (name == "STEP") return Interpolation::kStep;
    if (name == "CUBICSPLINE") return Interpolation::kCubicSpline;
    return absl::InvalidArgumentError(absl::StrCat(
        where, ": interpolation \"", name, "\" is unknown; expected LINEAR, STEP or CUBICSPLINE"));
}

absl::StatusOr<Keyframes> Keyframes::Create(Interpolation interpolation, KeyframeKind kind,
                                            int width, std::vector<double> times,
                                            std::vector<double> values, const std::string& where) {
    const auto fail = [&](const std::string& message) {
        return absl::InvalidArgumentError(absl::StrCat(where, ": ", message));
    };
    if (times.empty()) return fail("input has no keyframes");
    if (width < 1) return fail(absl::StrCat("output has ", width, " numbers per keyframe"));
    const bool cubic = interpolation == Interpolation::kCubicSpline;
    if (cubic && times.size() < 2) return fail("CUBICSPLINE needs at least 2 keyframes");
    for (size_t k = 0; k < times.size(); ++k) {
        if (!std::isfinite(times[k])) return fail(absl::StrCat("input time ", k, " is ", times[k]));
        if (k > 0 && !(times[k] > times[k - 1])) {
            return fail(absl::StrCat("input times are not strictly increasing: time ", k, " is ",
                                     times[k], " after ", times[k - 1]));
        }
    }
    const size_t per_key = size_t(width) * (cubic ? 3 : 1);
    if (values.size() != times.size() * per_key) {
        return fail(absl::StrCat("output has ", values.size(), " numbers for ", times.size(),
                                 " keyframes; expected ", times.size() * per_key,
                                 cubic ? " (CUBICSPLINE: in-tangent, value, out-tangent)" : ""));
    }
    for (size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i])) {
            return fail(absl::StrCat("output keyframe ", i / per_key, " (at ", times[i / per_key],
                                     " s) number ", i % per_key, " is ", values[i]));
        }
    }
    Keyframes out;
    out.interpolation_ = interpolation;
    out.kind_ = kind;
    out.width_ = width;
    out.times_ = std::move(times);
    out.values_ = std::move(values);
    if (kind == KeyframeKind::kRotation) {
        if (width != 4) return fail(absl::StrCat("a rotation has 4 numbers, not ", width));
        for (size_t k = 0; k < out.times_.size(); ++k) {
            const double* q = out.Value(k);
            if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 0)) {
                return fail(absl::StrCat("output keyframe ", k, " (at ", out.times_[k],
                                         " s) is the zero quaternion"));
            }
        }
    }
    return out;
}

const double* Keyframes::Value(size_t k) const {
    const bool cubic = interpolation_ == Interpolation::kCubicSpline;
    return values_.data() + k * size_t(width_) * (cubic ? 3 : 1) + (cubic ? size_t(width_) : 0);
}

void Keyframes::At(double seconds, std::span<double> out) const {
    const size_t w = size_t(width_);
    const auto hold = [&](size_t k) { std::copy_n(Value(k), w, out.begin()); };
    // k: the last key at or before `seconds`.
    const size_t n = times_.size();
    if (!(seconds > times_.front())) {
        hold(0);
    } else if (seconds >= times_.back()) {
        hold(n - 1);
    } else {
        const size_t k =
            size_t(std::upper_bound(times_.begin(), times_.end(), seconds) - times_.begin()) - 1;
        const double interval = times_[k + 1] - times_[k];
        const double s = (seconds - times_[k]) / interval;
        const double *a = Value(k), *b = Value(k + 1);
        switch (interpolation_) {
            case Interpolation::kStep:
                hold(k);
                break;
            case Interpolation::kLinear:
                if (kind_ == KeyframeKind::kRotation) {
                    Slerp(a, b, s, out);
                    return;
                }
                for (size_t c = 0; c < w; ++c) out[c] = (1 - s) * a[c] + s * b[c];
                break;
            case Interpolation::kCubicSpline: {
                // Hermite between the values with key k's out-tangent and key k+1's
                // in-tangent, both scaled by the interval.
                const double* out_tangent = a + w;
                const double* in_tangent = b - w;
                const double s2 = s * s, s3 = s2 * s;
                const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s,
                             h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
                for (size_t c = 0; c < w; ++c) {
                    out[c] = h00 * a[c] + h10 * interval * out_tangent[c] + h01 * b[c] +
                             h11 * interval * in_tangent[c];
                }
                break;
            }
        }
    }
    if (kind_ == KeyframeKind::kRotation) Normalize4(out);
}

std::vector<double> Keyframes::At(double seconds) const {
    std::vector<double> out(static_cast<size_t>(width_));
    At(seconds, out);
    return out;
}

}  // namespace lf
