// A radiosity sweep task on the wire: its sweep, chunks, input blob and (when the coordinator
// sends it inline, lf::kMaxInlineRadiosityBytes) the input's bytes reach the worker as leased;
// a task without inline bytes tells the worker to fetch the blob.
#include <gtest/gtest.h>

#include <memory>

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

}  // namespace
}  // namespace lf
