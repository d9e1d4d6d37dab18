#include "lf/core/piecewise_distribution.h"

#include <algorithm>
#include <cmath>

namespace lf {

namespace {
float Sanitised(float v) { return std::isfinite(v) && v > 0 ? v : 0.0f; }

// The row integrals of a 2D function: the marginal density's values.
std::vector<float> RowIntegrals(const std::vector<PiecewiseConstant1D>& rows) {
    std::vector<float> integrals;
    integrals.reserve(rows.size());
    for (const PiecewiseConstant1D& row : rows) integrals.push_back(float(row.Integral()));
    return integrals;
}

std::vector<PiecewiseConstant1D> Rows(std::span<const float> f, int nu, int nv) {
    std::vector<PiecewiseConstant1D> rows;
    rows.reserve(size_t(nv));
    for (int v = 0; v < nv; ++v) rows.emplace_back(f.subspan(size_t(v) * size_t(nu), size_t(nu)));
    return rows;
}
}  // namespace

PiecewiseConstant1D::PiecewiseConstant1D(std::span<const float> f)
    : f_(f.size()), cdf_(f.size() + 1, 0.0f) {
    const size_t n = f.size();
    std::vector<double> sum(n + 1, 0.0);
    for (size_t i = 0; i < n; ++i) {
        f_[i] = Sanitised(f[i]);
        sum[i + 1] = sum[i] + double(f_[i]) / double(n);
    }
    integral_ = sum[n];
    for (size_t i = 1; i <= n; ++i) {
        // Nothing to sample: uniform, so Sample still returns points (of density 0).
        cdf_[i] = float(integral_ > 0 ? sum[i] / integral_ : double(i) / double(n));
    }
    if (n > 0) cdf_[n] = 1;
}

float PiecewiseConstant1D::Sample(float u, float* pdf, int* piece) const {
    // The last piece whose CDF starts at or below u: it has positive width, since u < 1.
    const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    const int i = std::clamp(int(it - cdf_.begin()) - 1, 0, size() - 1);
    const double lo = cdf_[size_t(i)], width = double(cdf_[size_t(i) + 1]) - lo;
    const double du = width > 0 ? (double(u) - lo) / width : 0.5;
    *piece = i;
    *pdf = Density(i);
    // Rounding must not carry the point into the next piece, where the density differs.
    const float x = float((i + std::clamp(du, 0.0, 1.0)) / size());
    return std::min(x, std::nextafter(float(i + 1) / float(size()), 0.0f));
}

float PiecewiseConstant1D::Density(int piece) const {
    return integral_ > 0 ? float(double(f_[size_t(piece)]) / integral_) : 0.0f;
}

PiecewiseConstant2D::PiecewiseConstant2D(std::span<const float> f, int nu, int nv)
    : conditional_(Rows(f, nu, nv)), marginal_(RowIntegrals(conditional_)) {}

Vec2 PiecewiseConstant2D::Sample(const Vec2& u, float* pdf) const {
    float pdf_v = 0, pdf_u = 0;
    int row = 0, column = 0;
    const float v = marginal_.Sample(u.y, &pdf_v, &row);
    const float x = conditional_[size_t(row)].Sample(u.x, &pdf_u, &column);
    *pdf = pdf_u * pdf_v;
    return {x, v};
}

float PiecewiseConstant2D::Pdf(const Vec2& uv) const {
    const int nv = marginal_.size();
    const int row = std::clamp(int(uv.y * float(nv)), 0, nv - 1);
    const PiecewiseConstant1D& conditional = conditional_[size_t(row)];
    const int nu = conditional.size();
    const int column = std::clamp(int(uv.x * float(nu)), 0, nu - 1);
    return marginal_.Density(row) * conditional.Density(column);
}

}  // namespace lf
