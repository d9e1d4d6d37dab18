// A JobRecord as the coordinator's job store keeps it (lightfarm.v1.StoredJob): the settings go
// through the wire's own RenderParams conversion, so the store follows every new setting.
#pragma once

#include "absl/status/statusor.h"
#include "lf/job/job_record.h"
#include "lightfarm/v1/stored_job.pb.h"

namespace lf {

void ToProto(const JobRecord& job, lightfarm::v1::StoredJob* out);
// InvalidArgument for a state no build names.
absl::StatusOr<JobRecord> FromProto(const lightfarm::v1::StoredJob& stored);

void ToProto(const TaskHistory& history, lightfarm::v1::StoredTaskHistory* out);
TaskHistory FromProto(const lightfarm::v1::StoredTaskHistory& stored);

}  // namespace lf
