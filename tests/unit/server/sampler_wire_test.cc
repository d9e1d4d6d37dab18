// `--sampler` on the wire: what a client asks for is what the workers render, and a client from
// before the field, which sends none, gets the independent numbers its own `render` would use.
#include <gtest/gtest.h>

#include "lf/job/job_spec.h"
#include "lf/wire/conversions.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

TEST(SamplerWire, EachSamplerSurvivesTheWire) {
    for (const SamplerType sampler : {SamplerType::kSobol, SamplerType::kIndependent}) {
        JobSpec spec;
        spec.sampler = sampler;
        pb::RenderParams params;
        ToProto(spec, &params);
        JobSpec back;
        FromProto(params, &back);
        EXPECT_EQ(back.sampler, sampler) << SamplerTypeName(sampler);
    }
}

TEST(SamplerWire, AnOldClientsParamsMeanIndependentNumbers) {
    JobSpec spec;
    FromProto(pb::RenderParams{}, &spec);
    EXPECT_EQ(spec.sampler, SamplerType::kIndependent);
}

}  // namespace
}  // namespace lf
