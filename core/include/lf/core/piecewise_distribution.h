// Piecewise-constant distributions on [0, 1) and [0, 1)^2, sampled by inverting their CDFs
// (after pbrt-v4's PiecewiseConstant1D / 2D): what an environment map's importance sampling
// draws texels from. The 2D one is a marginal over rows times a conditional within each row.
#pragma once

#include <span>
#include <vector>

#include "lf/core/vec.h"

namespace lf {

class PiecewiseConstant1D {
  public:
    // f: the function's value on each of f.size() >= 1 equal pieces of [0, 1); non-negative and
    // finite (negative or non-finite values count as 0). An all-zero f samples uniformly but has
    // density 0 everywhere: there is nothing to sample.
    explicit PiecewiseConstant1D(std::span<const float> f);

    // A point of [0, 1) with density proportional to f, from u in [0, 1). Its density (with
    // respect to x) goes to *pdf and its piece to *piece.
    float Sample(float u, float* pdf, int* piece) const;
    // Density of piece i: f[i] / Integral().
    float Density(int piece) const;

    // The integral of f over [0, 1): the mean of its pieces.
    double Integral() const { return integral_; }
    int size() const { return int(f_.size()); }

  private:
    std::vector<float> f_;
    // size() + 1 entries, cdf_[0] = 0, cdf_.back() = 1; summed in double, stored in float (a
    // 16k x 8k environment map's rows hold 128 M entries).
    std::vector<float> cdf_;
    double integral_ = 0;
};

class PiecewiseConstant2D {
  public:
    // f: nu x nv values, row-major (f[v * nu + u]); v indexes rows.
    PiecewiseConstant2D(std::span<const float> f, int nu, int nv);

    // (u, v) in [0, 1)^2 with density proportional to f, and that density in *pdf.
    Vec2 Sample(const Vec2& u, float* pdf) const;
    // Density at (u, v) in [0, 1]^2 (clamped to the last piece at 1).
    float Pdf(const Vec2& uv) const;

    double Integral() const { return marginal_.Integral(); }

  private:
    std::vector<PiecewiseConstant1D> conditional_;  // per row
    PiecewiseConstant1D marginal_;                  // over rows, from each row's integral
};

}  // namespace lf
