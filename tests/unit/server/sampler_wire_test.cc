// `--sampler` and `--light-sampling` on the wire: what a client asks for is what the workers
// render, and a client from before the fields, which sends neither, gets the independent
// numbers and the lights picked by power that its own `render` would use.
#include <gtest/gtest.h>

#include <initializer_list>

#include "lf/job/job_spec.h"
#include "lf/wire/conversions.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

template <typename T>
void ExpectEachValueSurvivesTheWire(T JobSpec::*field, std::initializer_list<T> values,
                                    const char* (*name_of)(T)) {
    for (const T value : values) {
        JobSpec spec;
        spec.*field = value;
        pb::RenderParams params;
        ToProto(spec, &params);
        JobSpec back;
        FromProto(params, &back);
        EXPECT_EQ(back.*field, value) << name_of(value);
    }
}

TEST(SamplerWire, EachSamplerSurvivesTheWire) {
    ExpectEachValueSurvivesTheWire(
        &JobSpec::sampler, {SamplerType::kSobol, SamplerType::kIndependent}, &SamplerTypeName);
}

TEST(SamplerWire, EachLightStrategySurvivesTheWire) {
    ExpectEachValueSurvivesTheWire(
        &JobSpec::light_strategy, {LightStrategy::kBvh, LightStrategy::kPower}, &LightStrategyName);
}

TEST(SamplerWire, AnOldClientsParamsMeanIndependentNumbersAndLightsByPower) {
    JobSpec spec;
    FromProto(pb::RenderParams{}, &spec);
    EXPECT_EQ(spec.sampler, SamplerType::kIndependent);
    EXPECT_EQ(spec.light_strategy, LightStrategy::kPower);
}

}  // namespace
}  // namespace lf
