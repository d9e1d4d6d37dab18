// The stored form of a JobRecord, part of the JobStore interface: any store keeps records in
// this form, so that a second store reads what the first wrote. The wire's lightfarm.v1.StoredJob
// (lf/wire/stored_job.h) in protobuf's JSON with the proto field names: readable with the sqlite3
// shell, queried there by json_extract, and a new setting needs no change here. Records of the
// first JSON form are read by DecodeLegacyJobRecord (server/legacy_job_record.h).
#pragma once

#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/job/job_record.h"

namespace lf {

std::string EncodeJobRecord(const JobRecord& record);
// DataLoss, naming the field, for a record that does not parse or names an unknown state.
absl::StatusOr<JobRecord> DecodeJobRecord(std::string_view stored);

// A done task's history (lightfarm.v1.StoredTaskHistory), in the same JSON form.
std::string EncodeTaskHistory(const TaskHistory& history);
// DataLoss for one that does not parse; "" (a result recorded before histories were) is none.
absl::StatusOr<TaskHistory> DecodeTaskHistory(std::string_view stored);

}  // namespace lf
