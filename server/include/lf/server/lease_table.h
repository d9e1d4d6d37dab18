// Every lease of the running jobs, and the one owner of each lease's state: its job, task,
// attempt, holder, deadline, and whether it is still current. Lease ids are 128 random bits, so
// a worker cannot name another's lease by guessing, and an id is only ever looked up here, never
// read for what it says. A lease from before a restart is simply unknown.
//
// An ended lease (expired, failed, or its task finished or dropped) is kept until its job ends,
// so that its late result or heartbeat is still recognised as its holder's.
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "absl/time/time.h"

namespace lf {

struct Lease {
    std::string job_id;
    int task = 0;
    int attempt = 0;  // 1 for the task's first lease
    std::string worker;
    absl::Time deadline;
    bool current = true;
    // A heartbeat extended it: the worker took the task. A lease that expires unheard was
    // abandoned (or never reached its worker): the task is not to blame.
    bool heard = false;
};

// The principal a worker id belongs to: its token's name, which lf::WorkerIdentity puts before a
// '/'; "" for an id without one (authentication off).
std::string PrincipalOf(const std::string& worker);

// `digits` hex digits from std::random_device: unguessable ids.
std::string RandomHex(int digits);
inline std::string RandomLeaseId() { return RandomHex(32); }

class LeaseTable {
  public:
    using IdSource = std::function<std::string()>;
    explicit LeaseTable(IdSource new_id = RandomLeaseId) : new_id_(std::move(new_id)) {}

    // A new current lease; returns its id.
    std::string Grant(const std::string& job_id, int task, int attempt, const std::string& worker,
                      absl::Time deadline);
    // nullptr for an id this table never granted, or whose job it has forgotten.
    const Lease* Find(const std::string& lease_id) const;
    // Moves a current lease's deadline; false for an unknown or ended one.
    bool Extend(const std::string& lease_id, absl::Time deadline);
    // The lease is no longer current (its deadline forgotten); it stays known.
    void End(const std::string& lease_id);
    // Ends the task's current leases.
    void EndTask(const std::string& job_id, int task);
    // Ends and returns the current leases whose deadline is at or before `now`, earliest first.
    std::vector<std::string> TakeExpired(absl::Time now);
    // Forgets every lease of the job: their ids become unknown.
    void ForgetJob(const std::string& job_id);

    // The task's current leases, oldest first.
    std::vector<const Lease*> Current(const std::string& job_id, int task) const;
    // The holder of the task's newest lease; "" when it was never leased.
    std::string LastHolder(const std::string& job_id, int task) const;
    // The current lease each worker holds (of two, the one with the later deadline).
    std::map<std::string, const Lease*> CurrentByWorker() const;
    size_t current_count() const { return deadlines_.size(); }
    // Current leases held by workers of `principal` (PrincipalOf their id).
    int CurrentOf(const std::string& principal) const;
    // The workers holding current leases of the job (its max_workers cap counts them).
    std::set<std::string> WorkersOf(const std::string& job_id) const;

  private:
    using Deadlines = std::multimap<absl::Time, std::string>;
    struct Entry {
        Lease lease;
        Deadlines::iterator deadline;  // valid while current
    };
    void EndEntry(Entry& entry);

    IdSource new_id_;
    std::unordered_map<std::string, Entry> by_id_;
    Deadlines deadlines_;  // current leases only
    std::map<std::pair<std::string, int>, std::vector<std::string>> by_task_;  // ids by attempt
};

}  // namespace lf
