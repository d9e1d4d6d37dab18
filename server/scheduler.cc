#include "server/scheduler.h"

#include <random>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "lf/core/tile_codec.h"
#include "server/logging.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("scheduler"); }

std::string RandomHex(int digits) {
    static std::mt19937_64 rng{std::random_device{}()};
    static const char kHex[] = "0123456789abcdef";
    std::string hex;
    uint64_t bits = rng();
    for (int i = 0; i < digits; ++i, bits >>= 4) hex.push_back(kHex[bits & 15]);
    return hex;
}

std::string NewJobId() { return "job-" + RandomHex(10); }

}  // namespace

Scheduler::Scheduler(SchedulerOptions options, JobStore& store, Clock clock)
    : options_(options), store_(store), clock_(std::move(clock)), boot_(RandomHex(6)) {}

absl::StatusOr<std::string> Scheduler::Submit(const JobSpec& spec) {
    absl::StatusOr<std::vector<RenderTask>> plan = PlanRender(spec.plan);
    if (!plan.ok()) return plan.status();
    std::lock_guard<std::mutex> lock(mutex_);
    std::string id = NewJobId();
    while (active_.count(id) || store_.Get(id).ok()) id = NewJobId();
    auto job = std::make_unique<Job>(Job{{},
                                         *plan,
                                         std::vector<Task>(plan->size()),
                                         {},
                                         RenderMerger(spec.plan.width, spec.plan.height, *plan)});
    for (int i = 0; i < int(plan->size()); ++i) job->queued.insert(i);
    job->record.id = id;
    job->record.seq = next_seq_++;
    job->record.spec = spec;
    job->record.submitted = clock_();
    job->record.tasks_total = int(plan->size());
    if (absl::Status s = Save(*job); !s.ok()) return s;
    Log()->info("job={} queued: {} tasks, {}x{}, {} spp, priority {}", id, plan->size(),
                spec.plan.width, spec.plan.height, spec.plan.spp, spec.priority);
    active_[id] = std::move(job);
    return id;
}

absl::StatusOr<std::vector<std::string>> Scheduler::Recover() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> rendered;
    for (JobRecord& record : store_.List()) {
        next_seq_ = std::max(next_seq_, record.seq + 1);
        if (IsFinal(record.state) || active_.count(record.id)) continue;
        absl::StatusOr<std::vector<RenderTask>> plan = PlanRender(record.spec.plan);
        if (!plan.ok()) return plan.status();
        absl::StatusOr<std::map<int, std::string>> results = store_.TaskResults(record.id);
        if (!results.ok()) return results.status();
        const int width = record.spec.plan.width, height = record.spec.plan.height;
        auto job = std::make_unique<Job>(Job{std::move(record),
                                             *plan,
                                             std::vector<Task>(plan->size()),
                                             {},
                                             RenderMerger(width, height, *plan)});
        for (const auto& [t, bytes] : *results) {
            absl::StatusOr<TileSums> sums = DecodeTileSums(bytes);
            // The store wrote what merged before, so this cannot fail unless the file was
            // damaged; the task is then simply rendered again.
            if (!sums.ok() || !job->merger.Add(t, *sums).ok()) {
                Log()->warn("job={} task={}: the recorded result is unusable, rendering it again",
                            job->record.id, t);
                continue;
            }
            job->tasks[size_t(t)].state = TaskState::kDone;
        }
        for (int t = 0; t < int(plan->size()); ++t) {
            if (job->tasks[size_t(t)].state != TaskState::kDone) job->queued.insert(t);
        }
        job->record.tasks_done = int(job->merger.tasks_done());
        job->record.stats = job->merger.stats();
        job->record.tasks_running = 0;
        Log()->info("job={} recovered: {}/{} tasks done, {} leases handed out before",
                    job->record.id, job->record.tasks_done, job->record.tasks_total,
                    job->record.tasks_leased);
        if (job->merger.Complete()) rendered.push_back(job->record.id);
        Save(*job).IgnoreError();
        active_[job->record.id] = std::move(job);
    }
    return rendered;
}

bool Scheduler::OtherWorkersAlive(const std::string& worker, absl::Time now) const {
    for (const auto& [w, seen] : workers_seen_) {
        if (w != worker && now - seen < options_.lease) return true;
    }
    return false;
}

std::optional<Lease> Scheduler::LeaseTask(const std::string& worker, absl::Time wait_until) {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        if (std::optional<Lease> lease = TryLease(worker)) return lease;
        const uint64_t version = version_;
        if (shutdown_ || !changed_.wait_until(lock, absl::ToChronoTime(wait_until),
                                              [&] { return version_ != version || shutdown_; })) {
            return std::nullopt;
        }
    }
}

std::optional<Lease> Scheduler::TryLease(const std::string& worker) {
    const absl::Time now = clock_();
    workers_seen_[worker] = now;
    // A task that failed here goes to another worker when there is one.
    const bool avoid_repeats = OtherWorkersAlive(worker, now);
    Job* best = nullptr;
    int best_task = -1;
    for (auto& [id, job] : active_) {
        if (best && (job->record.spec.priority < best->record.spec.priority ||
                     (job->record.spec.priority == best->record.spec.priority &&
                      job->record.seq > best->record.seq))) {
            continue;
        }
        for (int t : job->queued) {
            if (avoid_repeats && job->tasks[size_t(t)].failed_on.count(worker)) continue;
            best = job.get();
            best_task = t;
            break;
        }
    }
    if (!best) return std::nullopt;
    Task& task = best->tasks[size_t(best_task)];
    best->queued.erase(best_task);
    task.state = TaskState::kLeased;
    ++task.attempts;
    ++best->record.tasks_leased;
    task.worker = worker;
    task.lease_id = absl::StrCat(best->record.id, "/", best_task, "/", boot_, "-", task.attempts);
    timeouts_.Set(task.lease_id, now + options_.lease);
    if (best->record.state == JobState::kQueued) {
        best->record.state = JobState::kRunning;
        best->record.started = now;
    }
    ++best->record.tasks_running;
    Save(*best).IgnoreError();
    Log()->debug("job={} task={} leased to {} (attempt {})", best->record.id, best_task, worker,
                 task.attempts);
    return Lease{task.lease_id, best->record.id, best->plan[size_t(best_task)], best->record.spec};
}

std::optional<Scheduler::LeaseRef> Scheduler::Resolve(const std::string& lease_id) {
    const std::vector<std::string> parts = absl::StrSplit(lease_id, '/');
    int task = 0;
    if (parts.size() != 3 || !absl::SimpleAtoi(parts[1], &task)) return std::nullopt;
    auto it = active_.find(parts[0]);
    if (it == active_.end() || task < 0 || size_t(task) >= it->second->tasks.size()) {
        return std::nullopt;
    }
    return LeaseRef{it->second.get(), task};
}

bool Scheduler::IsCurrent(const LeaseRef& ref, const std::string& lease_id) const {
    const Task& task = ref.job->tasks[size_t(ref.task)];
    return task.state == TaskState::kLeased && task.lease_id == lease_id;
}

bool Scheduler::Heartbeat(const std::string& lease_id, const std::string& worker) {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    workers_seen_[worker] = now;
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !IsCurrent(*ref, lease_id)) return false;
    timeouts_.Set(lease_id, now + options_.lease);
    return true;
}

absl::StatusOr<Scheduler::Completion> Scheduler::Complete(const std::string& lease_id,
                                                          const std::string& worker,
                                                          const TileSums& sums) {
    std::lock_guard<std::mutex> lock(mutex_);
    workers_seen_[worker] = clock_();
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref) {
        return absl::FailedPreconditionError(
            absl::StrCat("lease ", lease_id, ": its job is no longer running"));
    }
    Job& job = *ref->job;
    Task& task = job.tasks[size_t(ref->task)];
    if (task.state == TaskState::kDone) return Completion{job.record.id, false};
    if (absl::Status s = job.merger.Add(ref->task, sums); !s.ok()) {
        return absl::InvalidArgumentError(absl::StrCat("job=", job.record.id, " task=", ref->task,
                                                       " from ", worker, ": ", s.message()));
    }
    if (task.state == TaskState::kLeased) {
        // Whoever holds the lease now (maybe a retry elsewhere) learns at its next heartbeat.
        timeouts_.Remove(task.lease_id);
        --job.record.tasks_running;
    } else {
        job.queued.erase(ref->task);
    }
    task.state = TaskState::kDone;
    job.record.tasks_done = int(job.merger.tasks_done());
    job.record.stats = job.merger.stats();
    if (absl::Status s = store_.PutTaskDone(job.record, ref->task, EncodeTileSums(sums));
        !s.ok()) {
        // The merge cannot be taken back, and a job whose results are not all recorded would not
        // survive a restart: it fails here, and the worker hears why.
        const std::string job_id = job.record.id;
        FailJob(job, absl::StrCat("recording the result of task ", ref->task, ": ", s.message()));
        return absl::UnavailableError(absl::StrCat("job=", job_id, ": ", s.message()));
    }
    ++version_;
    changed_.notify_all();
    Log()->debug("job={} task={} done by {} ({}/{})", job.record.id, ref->task, worker,
                 job.record.tasks_done, job.record.tasks_total);
    return Completion{job.record.id, job.merger.Complete()};
}

absl::Status Scheduler::Fail(const std::string& lease_id, const std::string& worker,
                             const std::string& reason, FailureKind kind) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !IsCurrent(*ref, lease_id)) return absl::OkStatus();
    timeouts_.Remove(lease_id);
    Requeue(*ref->job, ref->task, absl::StrCat(reason, " (worker ", worker, ")"),
            kind == FailureKind::kTaskError);
    return absl::OkStatus();
}

void Scheduler::Requeue(Job& job, int t, const std::string& reason, bool counted) {
    Task& task = job.tasks[size_t(t)];
    task.state = TaskState::kQueued;
    --job.record.tasks_running;
    if (counted) {
        ++task.failures;
        task.failed_on.insert(task.worker);
    }
    Log()->warn("job={} task={} attempt {} failed: {}{}", job.record.id, t, task.attempts, reason,
                counted ? "" : " (not counted)");
    if (task.failures >= options_.max_failures) {
        FailJob(job, absl::StrCat("task ", t, " failed ", task.failures, " times; last: ", reason));
        return;
    }
    job.queued.insert(t);
    ++job.record.retries;
    Save(job).IgnoreError();
}

void Scheduler::FailJob(Job& job, const std::string& error) {
    job.record.state = JobState::kFailed;
    job.record.error = error;
    Log()->error("job={} failed: {}", job.record.id, error);
    EndJob(job);
}

void Scheduler::EndJob(Job& job) {
    job.record.finished = clock_();
    job.record.tasks_running = 0;
    for (const Task& task : job.tasks) {
        if (task.state == TaskState::kLeased) timeouts_.Remove(task.lease_id);
    }
    Save(job).IgnoreError();
    active_.erase(job.record.id);  // destroys `job`
}

absl::StatusOr<JobRecord> Scheduler::Cancel(const std::string& job_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) {
        absl::StatusOr<JobRecord> record = store_.Get(job_id);
        if (!record.ok()) return record.status();
        return absl::FailedPreconditionError(
            absl::StrCat("job ", job_id, " has already ended (", JobStateName(record->state), ")"));
    }
    it->second->record.state = JobState::kCancelled;
    EndJob(*it->second);
    Log()->info("job={} cancelled", job_id);
    return store_.Get(job_id);
}

int Scheduler::ExpireLeases() {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::vector<std::string> expired = timeouts_.TakeExpired(clock_());
    for (const std::string& lease_id : expired) {
        const std::optional<LeaseRef> ref = Resolve(lease_id);
        if (!ref || !IsCurrent(*ref, lease_id)) continue;
        const std::string& worker = ref->job->tasks[size_t(ref->task)].worker;
        Requeue(*ref->job, ref->task,
                absl::StrCat("lease expired: worker ", worker, " sent no heartbeat for ",
                             absl::FormatDuration(options_.lease)),
                true);
    }
    return int(expired.size());
}

absl::StatusOr<std::pair<JobRecord, Image>> Scheduler::Snapshot(const std::string& job_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) {
        return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
    }
    return std::pair{it->second->record, it->second->merger.Snapshot()};
}

void Scheduler::Finish(const std::string& job_id, const absl::StatusOr<std::string>& result_path) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return;  // cancelled meanwhile
    Job& job = *it->second;
    if (!result_path.ok()) {
        FailJob(job, absl::StrCat("writing the result: ", result_path.status().message()));
        return;
    }
    job.record.state = JobState::kSucceeded;
    job.record.result_path = *result_path;
    Log()->info("job={} succeeded: {} samples -> {}", job_id, job.record.stats.samples,
                *result_path);
    EndJob(job);
}

absl::Status Scheduler::Save(Job& job) {
    absl::Status s = store_.Put(job.record);
    if (!s.ok()) Log()->error("job={} not saved: {}", job.record.id, std::string(s.message()));
    ++version_;
    changed_.notify_all();
    return s;
}

uint64_t Scheduler::WaitForChange(uint64_t version, absl::Time deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_until(lock, absl::ToChronoTime(deadline),
                        [&] { return version_ != version || shutdown_; });
    return version_;
}

void Scheduler::Shutdown() {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
    changed_.notify_all();
}

}  // namespace lf
