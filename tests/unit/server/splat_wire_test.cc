// The splatting methods on the wire: a ppm job's photon settings, and a splat task's camera part and
// light-path range, reach the worker as the client and the coordinator gave them; a params
// message without photon settings means the defaults; a job record keeps them across a
// coordinator restart.
#include <gtest/gtest.h>

#include "legacy_job_records.h"
#include "lf/job/job_spec.h"
#include "lf/job/task_assignment.h"
#include "lf/wire/conversions.h"
#include "nlohmann/json.hpp"
#include "lf/server/job_record_codec.h"
#include "lf/server/legacy_job_record.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

TEST(SplatWire, PhotonSettingsSurviveTheWire) {
    JobSpec spec;
    spec.method = "ppm";
    spec.ppm = {12345, 0.25, 0.8};
    pb::RenderParams params;
    ToProto(spec, &params);
    JobSpec back;
    FromProto(params, &back);
    EXPECT_EQ(back.method, "ppm");
    EXPECT_EQ(back.ppm.photons_per_pass, 12345u);
    EXPECT_EQ(back.ppm.initial_radius, 0.25);
    EXPECT_EQ(back.ppm.alpha, 0.8);
}

TEST(SplatWire, MissingPhotonSettingsMeanTheDefaults) {
    pb::RenderParams params;
    params.set_method("ppm");
    params.mutable_ppm();  // present, every field zero
    JobSpec back;
    FromProto(params, &back);
    EXPECT_EQ(back.ppm.photons_per_pass, defaults::kPpmPhotonsPerPass);
    EXPECT_EQ(back.ppm.alpha, defaults::kPpmAlpha);
    EXPECT_EQ(back.ppm.initial_radius, 0.0);
    EXPECT_TRUE(CheckPhotonSettings(back.ppm).ok());
}

TEST(SplatWire, SplatTaskRangesSurviveTheWire) {
    for (const char* method : {"light", "bdpt", "ppm"}) {
        TaskAssignment a;
        a.lease_id = "l";
        a.job_id = "j";
        a.spec.method = method;
        a.task = {7, {8, 16, 8, 4}, 2, 5};
        a.path_begin = uint64_t(1) << 40;
        a.path_end = (uint64_t(1) << 40) + 65536;
        pb::Task t;
        ToProto(a, &t);
        EXPECT_EQ(t.kind(), pb::Task::FRAME) << method;
        const TaskAssignment back = FromProto(t);
        EXPECT_EQ(back.spec.method, method);
        EXPECT_EQ(back.task.index, 7);
        EXPECT_EQ(back.task.rect.y0, 16);
        EXPECT_EQ(back.task.rect.height, 4);
        EXPECT_EQ(back.task.sample_end, 5u);
        EXPECT_EQ(back.path_begin, a.path_begin);
        EXPECT_EQ(back.path_end, a.path_end);
        EXPECT_EQ(back.sweep, -1);
    }
    TaskAssignment tile;
    tile.spec.method = "path";
    pb::Task t;
    ToProto(tile, &t);
    EXPECT_EQ(t.kind(), pb::Task::TILE);
}

TEST(SplatWire, PhotonSettingsSurviveTheJobRecordAndOldRecordsHaveTheDefaults) {
    JobRecord job;
    job.id = "a";
    job.seq = 1;
    job.spec.method = "ppm";
    job.spec.ppm = {999, 0.5, 0.6};
    nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(job));
    absl::StatusOr<JobRecord> back = DecodeJobRecord(stored.dump());
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.ppm.photons_per_pass, 999u);
    EXPECT_EQ(back->spec.ppm.initial_radius, 0.5);
    EXPECT_EQ(back->spec.ppm.alpha, 0.6);
    stored = nlohmann::json::parse(testing::kLegacyRepresentativeRecords[3]);  // ppm, 500000
    stored["spec"].erase("ppm");
    back = DecodeLegacyJobRecord(stored.dump());
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.ppm.photons_per_pass, defaults::kPpmPhotonsPerPass);
}

}  // namespace
}  // namespace lf
