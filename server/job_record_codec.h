// The stored form of a JobRecord, part of the JobStore interface: any store keeps records in
// this form, so that a second store reads what the first wrote. JSON: readable with the sqlite3
// shell, and new fields need no schema change. States are stored by name ("running"), never by
// enum position.
#pragma once

#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/job/job_record.h"

namespace lf {

std::string EncodeJobRecord(const JobRecord& record);
// DataLoss, naming the field, for a record that does not parse or names an unknown state.
// Reads the integer states that records written before names were stored carry.
absl::StatusOr<JobRecord> DecodeJobRecord(std::string_view stored);

// The state named `name` (JobStateName's inverse); InvalidArgument for any other name.
absl::StatusOr<JobState> JobStateFromName(std::string_view name);

}  // namespace lf
