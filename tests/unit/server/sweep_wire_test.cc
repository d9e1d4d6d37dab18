// A radiosity sweep task on the wire: its sweep, chunks, input blob and (when the coordinator
// sends it inline, lf::kMaxInlineRadiosityBytes) the input's bytes reach the worker as leased;
// a task without inline bytes tells the worker to fetch the blob.
#include <gtest/gtest.h>

#include <memory>

#include "lf/job/plan.h"
#include "lf/server/read_after_auth.h"
#include "lf/wire/conversions.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

TaskAssignment SweepTask() {
    TaskAssignment lease;
    lease.spec.method = "radiosity";
    lease.sweep = 3;
    lease.chunks = {1, 4, 6};
    lease.radiosity_hash = std::string(64, 'a');
    return lease;
}

TEST(SweepWire, ASweepTasksInputTravelsInlineOrByItsBlob) {
    TaskAssignment lease = SweepTask();
    // Bytes of every value, a zero among them: the field is bytes, not text.
    std::string input(300, '\0');
    for (size_t i = 0; i < input.size(); ++i) input[i] = char(i * 7);
    lease.radiosity_input = std::make_shared<const std::string>(input);
    pb::Task task;
    ToProto(lease, &task);
    EXPECT_EQ(task.kind(), pb::Task::RADIOSITY_SWEEP);
    TaskAssignment back = FromProto(task);
    EXPECT_EQ(back.sweep, 3);
    EXPECT_EQ(back.chunks, (std::vector<int>{1, 4, 6}));
    EXPECT_EQ(back.radiosity_hash, lease.radiosity_hash);
    ASSERT_NE(back.radiosity_input, nullptr);
    EXPECT_EQ(*back.radiosity_input, input);

    // Stored as a blob (large, or a coordinator from before the field): the worker fetches it.
    pb::Task by_blob;
    ToProto(SweepTask(), &by_blob);
    EXPECT_TRUE(by_blob.radiosity_input().empty());
    back = FromProto(by_blob);
    EXPECT_EQ(back.radiosity_hash, std::string(64, 'a'));
    EXPECT_EQ(back.radiosity_input, nullptr);
}

// The largest lease a worker may be sent: the spec of the largest submission the coordinator
// takes (kMaxRequestBytes, here tens of thousands of mesh files) and a sweep's input inline.
// The worker's channel takes kMaxLeaseBytes; above it the lease would be lost in transit and
// the job would hang.
TEST(SweepWire, TheLargestLeaseFitsTheWorkersReceiveLimit) {
    pb::SubmitJobRequest request;
    request.mutable_scene()->set_path("scene.json");
    request.mutable_scene()->set_hash(std::string(64, 'b'));
    request.mutable_params()->set_method("radiosity");
    // Each file costs its own bytes and at most 3 of tag and length.
    for (size_t i = 0, size = request.ByteSizeLong(); size < kMaxRequestBytes - 256; ++i) {
        pb::SceneFile* file = request.add_files();
        file->set_path("meshes/a_rather_long_directory_name/part_" + std::to_string(i) + ".ply");
        file->set_hash(std::string(64, 'c'));
        file->set_size(uint64_t(1) << 40);
        size += file->ByteSizeLong() + 3;
    }
    ASSERT_LE(request.ByteSizeLong(), kMaxRequestBytes);
    ASSERT_GT(request.ByteSizeLong(), kMaxRequestBytes - 256 - 3 * size_t(request.files_size()));
    TaskAssignment lease = SweepTask();
    lease.spec = FromProto(request);
    lease.lease_id = std::string(64, 'l');
    lease.job_id = "job-0123456789";
    lease.chunks.assign(size_t(kMaxSweepTasks), 0);  // every chunk of the largest split
    lease.radiosity_input =
        std::make_shared<const std::string>(std::string(kMaxInlineRadiosityBytes, '\x7f'));
    pb::Task task;
    ToProto(lease, &task);
    EXPECT_GT(task.ByteSizeLong(), kMaxRequestBytes);
    EXPECT_LE(task.ByteSizeLong(), kMaxLeaseBytes);
}

}  // namespace
}  // namespace lf
