// Small fixed-size vectors: Vec3 (float, for rendering) and Vec3d (double, for scene input).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lf {

template <typename T>
struct Vec3T {
    T x = 0, y = 0, z = 0;

    constexpr Vec3T() = default;
    constexpr Vec3T(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <typename U>
    constexpr explicit Vec3T(const Vec3T<U>& v) : x(T(v.x)), y(T(v.y)), z(T(v.z)) {}

    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    constexpr Vec3T operator+(const Vec3T& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3T operator-(const Vec3T& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3T operator-() const { return {-x, -y, -z}; }
    constexpr Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3T& operator+=(const Vec3T& o) { return *this = *this + o; }
    constexpr Vec3T& operator-=(const Vec3T& o) { return *this = *this - o; }
    constexpr Vec3T& operator*=(T s) { return *this = *this * s; }
    constexpr bool operator==(const Vec3T&) const = default;
};

template <typename T>
constexpr Vec3T<T> operator*(T s, const Vec3T<T>& v) {
    return v * s;
}

template <typename T>
constexpr T Dot(const Vec3T<T>& a, const Vec3T<T>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <typename T>
constexpr T AbsDot(const Vec3T<T>& a, const Vec3T<T>& b) {
    return std::abs(Dot(a, b));
}

template <typename T>
constexpr Vec3T<T> Cross(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

template <typename T>
T LengthSquared(const Vec3T<T>& v) {
    return Dot(v, v);
}

template <typename T>
T Length(const Vec3T<T>& v) {
    return std::sqrt(Dot(v, v));
}

template <typename T>
Vec3T<T> Normalize(const Vec3T<T>& v) {
    return v / Length(v);
}

template <typename T>
Vec3T<T> Abs(const Vec3T<T>& v) {
    return {std::abs(v.x), std::abs(v.y), std::abs(v.z)};
}

template <typename T>
Vec3T<T> Min(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}

template <typename T>
Vec3T<T> Max(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

template <typename T>
T MaxComponent(const Vec3T<T>& v) {
    return std::max(v.x, std::max(v.y, v.z));
}

template <typename T>
bool IsFinite(const Vec3T<T>& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// The normal flipped, if needed, into the hemisphere of v.
template <typename T>
Vec3T<T> FaceForward(const Vec3T<T>& n, const Vec3T<T>& v) {
    return Dot(n, v) < 0 ? -n : n;
}

using Vec3 = Vec3T<float>;
using Vec3d = Vec3T<double>;

struct Vec2 {
    float x = 0, y = 0;
};

// An orthonormal basis around a unit normal (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited"): continuous everywhere except the one branch on the sign of z.
struct Frame {
    Vec3 s, t, n;

    static Frame FromNormal(const Vec3& n) {
        const float sign = std::copysign(1.0f, n.z);
        const float a = -1.0f / (sign + n.z);
        const float b = n.x * n.y * a;
        return {Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x),
                Vec3(b, sign + n.y * n.y * a, -n.y), n};
    }
    Vec3 ToLocal(const Vec3& v) const { return {Dot(v, s), Dot(v, t), Dot(v, n)}; }
    Vec3 FromLocal(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace lf
