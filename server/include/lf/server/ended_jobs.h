// Jobs that ended while their final record is queued but not yet durable, and those the store
// could not record: readers and retried submissions find them here until the store has them.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "lf/job/job_record.h"

namespace lf {

class EndedJobs {
  public:
    // A job that ended, its final record queued in the store as `ticket`. Returns the record.
    const JobRecord& Add(JobRecord record, uint64_t ticket);
    const JobRecord* Find(const std::string& job_id) const;
    // Whether the job's final record is queued but not yet settled (see Settle).
    bool IsSettling(const std::string& job_id) const { return ending_.count(job_id) > 0; }
    // The job of a submission with this request id, and the store ticket to wait for.
    std::optional<std::pair<std::string, uint64_t>> FindRequest(
        const std::string& request_id) const;
    // The blobs their specs read.
    void AddBlobsInUse(std::set<std::string>& hashes) const;

    bool has_unsettled() const { return !to_settle_.empty(); }
    // The jobs added since the last call, with the tickets to wait for.
    std::vector<std::pair<std::string, uint64_t>> TakeUnsettled();
    // What the store said of a job's final record: durable, the store has it; else it stays
    // here, not recorded (logged), so that readers still learn how it ended.
    void Settle(const std::string& job_id, const absl::Status& durable);

  private:
    struct Ending {
        JobRecord record;
        uint64_t ticket = 0;
    };
    std::map<std::string, Ending> ending_;
    std::vector<std::string> to_settle_;           // in `ending_`, not yet waited for
    std::map<std::string, JobRecord> unrecorded_;  // ended while the store could not write
};

}  // namespace lf
