// The defaults of every render setting, in one place: `render`, `submit`, `plan`, `converge`,
// `bench`, the coordinator and the workers all take theirs from here (through JobSpec,
// RenderPlanSettings, RadiositySettings and AdaptiveSettings, whose members start at these), so
// the same command line means the same render locally and on the farm.
#pragma once

#include <cstdint>

#include "lf/core/light_strategy.h"
#include "lf/core/sampler.h"

namespace lf::defaults {

inline constexpr uint64_t kSpp = 16;
inline constexpr uint64_t kSeed = 0;
inline constexpr int kTile = 32;
inline constexpr int kPasses = 1;
inline constexpr int kMaxDepth = -1;  // unlimited: Russian roulette ends paths
inline constexpr const char* kMethod = "path";
// Owen-scrambled Sobol points ("sobol"): lower error at equal samples than "independent".
inline constexpr SamplerType kSampler = SamplerType::kSobol;
// Lights picked by their importance at the shading point with a light BVH, triangles and spheres
// sampled by solid angle ("bvh"): the same mean as "power" with less variance among many lights
// or near large ones (docs/rendering.md).
inline constexpr LightStrategy kLightStrategy = LightStrategy::kBvh;
inline constexpr uint64_t kAdaptiveMaxSpp = uint64_t(1) << 16;

inline constexpr int64_t kRadiosityPatches = 4000;
// Jacobi: the farm splits each of its sweeps into patch-group tasks, and in one process it is
// about as fast as Gauss-Seidel (docs/radiosity.md), so one solver serves both.
inline constexpr const char* kRadiositySolver = "jacobi";
inline constexpr double kRadiosityTolerance = 1e-4;
inline constexpr int kRadiosityMaxIterations = 10000;
inline constexpr const char* kRadiosityDisplay = "smooth";
// Flat form factors (n^2, the reference) or hierarchical radiosity with clustering.
inline constexpr const char* kRadiosityForm = "flat";
inline constexpr double kRadiosityLinkError = 1e-4;
inline constexpr int kRadiositySweepTasks = 8;

// Progressive photon mapping (`ppm`, lf/job/splat_settings.h): photons traced per pass, the
// radius of pass 0 (0: the kernel chooses it from the scene's size and the frame) and alpha of
// Knaus & Zwicker's radius schedule r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1), so r_i^2 falls as
// i^(alpha - 1): after N passes the average's variance falls as N^-alpha and its bias as
// N^(alpha - 1); a larger alpha trades bias for less noise, 2/3 (theirs) balances the two.
inline constexpr uint64_t kPpmPhotonsPerPass = uint64_t(1) << 18;
inline constexpr double kPpmInitialRadius = 0;
inline constexpr double kPpmAlpha = 2.0 / 3.0;

}  // namespace lf::defaults
