#include "lf/client/sample_flags.h"

#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"

namespace lf {

namespace {

// A flag that takes one of two names (`first|second`) into `value` through the setting's own
// name functions, refusing any other name as "FLAG NAME: expected first or second"; the help
// ends with the default, the name `value` holds.
template <typename T>
void AddChoiceFlag(CLI::App* cmd, const std::string& flag, T& value,
                   std::optional<T> (*from_name)(std::string_view), const char* (*name_of)(T),
                   const std::string& first, const std::string& second, const std::string& help) {
    cmd->add_option_function<std::string>(
           flag,
           [&value, flag, from_name, first, second](const std::string& name) {
               const std::optional<T> parsed = from_name(name);
               if (!parsed) {
                   throw CLI::ValidationError(
                       absl::StrCat(flag, " ", name, ": expected ", first, " or ", second));
               }
               value = *parsed;
           },
           absl::StrCat(help, " Default ", name_of(value)))
        ->type_name(first + "|" + second);
}

}  // namespace

void AddSamplerFlag(CLI::App* cmd, SamplerType& sampler) {
    AddChoiceFlag(cmd, "--sampler", sampler, &SamplerTypeFromName, &SamplerTypeName, "independent",
                  "sobol",
                  "where each sample's random numbers come from: sobol (Owen-scrambled Sobol "
                  "points, stratified and low-discrepancy in every pair of dimensions a path "
                  "uses, so on smooth integrands the error falls faster than spp^-1/2) or "
                  "independent (the older hashed random numbers, error as spp^-1/2, for "
                  "comparison); both are pure functions of seed, pixel and sample, so tiles, "
                  "passes and workers give the same bits.");
}

void AddLightSamplingFlag(CLI::App* cmd, LightStrategy& strategy) {
    AddChoiceFlag(cmd, "--light-sampling", strategy, &LightStrategyFromName, &LightStrategyName,
                  "power", "bvh",
                  "how the path tracer picks a light and a point on it at each vertex: bvh (a "
                  "light BVH weighs every light by its importance at the shading point, and "
                  "triangles and spheres that look large are sampled by the solid angle they "
                  "subtend: less noise among many lights or near large ones) or power (a light "
                  "with probability proportional to its power, a point on it by area, as before "
                  "bvh existed, for comparison); both are unbiased, the same image on average.");
}

void AddClampFlag(CLI::App* cmd, double& clamp) {
    cmd->add_option_function<double>(
           "--clamp",
           [&clamp](double l) {
               if (!(l >= 0) || !std::isfinite(l)) {
                   throw CLI::ValidationError(
                       absl::StrCat("--clamp ", l, ": expected a radiance >= 0 (0 = off)"));
               }
               clamp = l;
           },
           "scale each sample down so that no channel of its radiance exceeds L W m^-2 sr^-1, "
           "to tame fireflies; 0 = off (default). Biased: it removes energy, and the estimated "
           "error does not include that bias (the EXR says so in lightfarm.bias)")
        ->type_name("L");
}

void AddSampleFlags(CLI::App* cmd, SamplerType& sampler, LightStrategy& light_strategy,
                    double& clamp, uint32_t& aovs) {
    AddSamplerFlag(cmd, sampler);
    AddLightSamplingFlag(cmd, light_strategy);
    AddClampFlag(cmd, clamp);
    cmd->add_option_function<std::string>(
           "--aov",
           [&aovs](const std::string& list) {
               absl::StatusOr<uint32_t> parsed = ParseAovList(list);
               if (!parsed.ok()) {
                   throw CLI::ValidationError(
                       absl::StrCat("--aov ", list, ": ", parsed.status().message()));
               }
               aovs = *parsed;
           },
           "auxiliary EXR channels of each pixel's first hits, averaged over its samples: "
           "albedo (albedo.R,G,B), normal (normal.X,Y,Z: world-space shading normal), depth "
           "(depth.Z: distance along the ray, scene units), illuminance (illuminance: lux on "
           "the side the camera sees, estimated with one extra light path a sample; path and "
           "radiosity only); a comma-separated list, or all (albedo, normal and depth)")
        ->type_name("LIST");
}

}  // namespace lf
