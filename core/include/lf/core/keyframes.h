// glTF 2.0 animation samplers (the specification's "Animations" section and its Appendix C):
// keyframe times and values, and the value they give at any time.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace lf {

enum class Interpolation { kLinear, kStep, kCubicSpline };

// Rotations are unit quaternions (x, y, z, w): LINEAR slerps them along the shortest arc and
// every interpolated rotation is normalised. Anything else (translations, scales, morph
// weights) interpolates component by component.
enum class KeyframeKind { kVector, kRotation };

class Keyframes {
  public:
    // `values` holds `width` numbers per key; CUBICSPLINE 3 * width, in glTF's order: in-tangent,
    // value, out-tangent. InvalidArgument starting with `where` ("animations[0].samplers[1]")
    // and naming the key (its index, and its time once the times are valid) when the times are
    // empty, not finite or not strictly increasing, the counts do not match, a value is not
    // finite, or a rotation key is the zero quaternion.
    static absl::StatusOr<Keyframes> Create(Interpolation interpolation, KeyframeKind kind,
                                            int width, std::vector<double> times,
                                            std::vector<double> values, const std::string& where);

    // The channel's `width` numbers at `seconds`; before the first key and after the last it
    // holds the first or last value.
    void At(double seconds, std::span<double> out) const;
    std::vector<double> At(double seconds) const;

    int width() const { return width_; }
    Interpolation interpolation() const { return interpolation_; }
    const std::vector<double>& times() const { return times_; }
    double start() const { return times_.front(); }
    double end() const { return times_.back(); }

  private:
    Keyframes() = default;
    // Key k's value (CUBICSPLINE: the middle of its three).
    const double* Value(size_t k) const;

    Interpolation interpolation_ = Interpolation::kLinear;
    KeyframeKind kind_ = KeyframeKind::kVector;
    int width_ = 0;
    std::vector<double> times_, values_;
};

// glTF's interpolation name ("LINEAR", "STEP", "CUBICSPLINE"); InvalidArgument naming `where`
// for anything else.
absl::StatusOr<Interpolation> ParseInterpolation(const std::string& name, const std::string& where);

}  // namespace lf
