// Fresnel reflectance for unpolarised light (pbrt-v4, "Specular Reflection and Transmission").
#pragma once

#include <complex>

#include "lf/core/rgb.h"

namespace lf {

// Dielectric interface; eta is the IOR of the side the normal points away from (inside) over
// the IOR of the side it points into. A negative cos_theta_i means light arriving from inside.
// Returns 1 under total internal reflection.
float FrDielectric(float cos_theta_i, float eta);

// Conductor with complex IOR eta + i k relative to the outside; cos_theta_i is clamped to
// [0, 1]. With k = 0 this equals FrDielectric, total internal reflection included.
float FrComplex(float cos_theta_i, std::complex<float> eta);
Rgb FrComplex(float cos_theta_i, const Rgb& eta, const Rgb& k);

// Schlick's approximation: f0 at normal incidence, rising to 1 at grazing.
Rgb FrSchlick(const Rgb& f0, float cos_theta_i);

}  // namespace lf
