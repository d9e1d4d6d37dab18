#include "sample_flags.h"

#include <cmath>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"

namespace lf {

void AddSamplerFlag(CLI::App* cmd, SamplerType& sampler) {
    cmd->add_option_function<std::string>(
           "--sampler",
           [&sampler](const std::string& name) {
               const std::optional<SamplerType> type = SamplerTypeFromName(name);
               if (!type) {
                   throw CLI::ValidationError(
                       absl::StrCat("--sampler ", name, ": expected independent or sobol"));
               }
               sampler = *type;
           },
           absl::StrCat(
               "where each sample's random numbers come from: sobol (Owen-scrambled Sobol "
               "points, stratified and low-discrepancy in every pair of dimensions a path uses, "
               "so on smooth integrands the error falls faster than spp^-1/2) or independent "
               "(the older hashed random numbers, error as spp^-1/2, for comparison); both are "
               "pure functions of seed, pixel and sample, so tiles, passes and workers give the "
               "same bits. Default ",
               SamplerTypeName(sampler)))
        ->type_name("independent|sobol");
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

void AddSampleFlags(CLI::App* cmd, SamplerType& sampler, double& clamp, uint32_t& aovs) {
    AddSamplerFlag(cmd, sampler);
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
           "(depth.Z: distance along the ray, scene units); a comma-separated list or all")
        ->type_name("LIST");
}

}  // namespace lf
