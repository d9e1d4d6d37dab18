// The first stored form of a JobRecord, a JSON object of its own (schema versions 0 and 1 of
// server/sqlite_job_store.h), read once to upgrade a store to the StoredJob form.
#pragma once

#include <string_view>

#include "absl/status/statusor.h"
#include "lf/job/job_record.h"

namespace lf {

// DataLoss, naming the field, for a record that does not parse or names an unknown state,
// filter, sampler or light strategy. Reads the integer states of records written before states
// were stored by name, and the defaults of settings older records lack.
absl::StatusOr<JobRecord> DecodeLegacyJobRecord(std::string_view stored);

}  // namespace lf
