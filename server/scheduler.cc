#include "server/scheduler.h"

#include <random>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "lf/core/log.h"
#include "lf/core/tile_codec.h"

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

absl::StatusOr<std::unique_ptr<Scheduler::Job>> Scheduler::NewJob(JobRecord record) {
    const JobSpec& spec = record.spec;
    auto job = std::make_unique<Job>(Job{std::move(record), nullptr});
    if (IsAdaptive(spec.adaptive)) {
        absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> plan = AdaptiveTilePlan::Make(
            spec.plan.width, spec.plan.height, spec.plan.spp, spec.plan.tile, spec.adaptive);
        if (!plan.ok()) return plan.status();
        job->adaptive = plan->get();
        job->merger = std::move(*plan);
    } else {
        absl::StatusOr<std::vector<RenderTask>> plan = PlanRender(spec.plan);
        if (!plan.ok()) return plan.status();
        job->merger = std::make_unique<RenderMerger>(spec.plan.width, spec.plan.height, *plan);
    }
    job->tasks.resize(job->merger->tasks().size());
    return job;
}

absl::StatusOr<std::string> Scheduler::Submit(const JobSpec& spec) {
    JobRecord record;
    record.spec = spec;
    absl::StatusOr<std::unique_ptr<Job>> made = NewJob(std::move(record));
    if (!made.ok()) return made.status();
    std::unique_ptr<Job> job = std::move(*made);
    QueueStart(*job);
    job->record.submitted = clock_();
    // The image's tasks: a radiosity solve's sweep tasks are not done the way tiles are.
    job->record.tasks_total = int(job->merger->tasks().size());
    std::unique_lock<std::mutex> lock(mutex_);
    if (std::optional<std::pair<std::string, uint64_t>> earlier = FindRequest(spec.request_id)) {
        lock.unlock();
        if (absl::Status s = store_.WaitDurable(earlier->second); !s.ok()) return s;
        Log()->info("job={} submitted again (request {})", earlier->first, spec.request_id);
        return earlier->first;
    }
    std::string id = NewJobId();
    while (active_.count(id) || store_.Get(id).ok()) id = NewJobId();
    job->record.id = id;
    job->record.seq = next_seq_++;
    const uint64_t ticket = Save(*job);
    job->submit_ticket = ticket;
    const size_t job_tasks = job->tasks.size();
    active_[id] = std::move(job);
    lock.unlock();
    // Acknowledged only once durable; waiting outside the lock lets submissions and results
    // share one sync.
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        Log()->error("job={} refused: {}", id, std::string(s.message()));
        lock.lock();
        active_.erase(id);
        return s;
    }
    if (IsAdaptive(spec.adaptive)) {
        Log()->info(
            "job={} queued: {} tiles, {}x{}, first pass {} spp, adaptive up to {} spp, target "
            "error {}, time limit {} s, priority {}",
            id, job_tasks, spec.plan.width, spec.plan.height, spec.plan.spp, spec.adaptive.max_spp,
            spec.adaptive.target_error, spec.adaptive.time_limit, spec.priority);
    } else {
        Log()->info("job={} queued: {} tasks, {}x{}, {} spp, priority {}", id, job_tasks,
                    spec.plan.width, spec.plan.height, spec.plan.spp, spec.priority);
    }
    return id;
}

std::optional<std::pair<std::string, uint64_t>> Scheduler::FindRequest(
    const std::string& request_id) const {
    if (request_id.empty()) return std::nullopt;
    for (const auto& [id, job] : active_) {
        if (job->record.spec.request_id == request_id) return std::pair{id, job->submit_ticket};
    }
    if (std::optional<std::string> id = store_.FindRequest(request_id)) {
        return std::pair{*id, uint64_t(0)};
    }
    return std::nullopt;
}

absl::StatusOr<JobRecord> Scheduler::Get(const std::string& job_id) const {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (auto it = active_.find(job_id); it != active_.end()) return it->second->record;
        if (auto it = unrecorded_.find(job_id); it != unrecorded_.end()) return it->second;
    }
    return store_.Get(job_id);
}

std::vector<JobRecord> Scheduler::List() const {
    std::vector<JobRecord> jobs = store_.List();
    std::lock_guard<std::mutex> lock(mutex_);
    for (JobRecord& job : jobs) {
        if (auto it = active_.find(job.id); it != active_.end()) job = it->second->record;
        if (auto it = unrecorded_.find(job.id); it != unrecorded_.end()) job = it->second;
    }
    return jobs;
}

absl::StatusOr<std::vector<std::string>> Scheduler::Recover() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> rendered;
    for (JobRecord& record : store_.List()) {
        next_seq_ = std::max(next_seq_, record.seq + 1);
        if (IsFinal(record.state) || active_.count(record.id)) continue;
        absl::StatusOr<std::map<int, std::string>> results = store_.TaskResults(record.id);
        if (!results.ok()) return results.status();
        absl::StatusOr<std::unique_ptr<Job>> made = NewJob(std::move(record));
        if (!made.ok()) return made.status();
        std::unique_ptr<Job> job = std::move(*made);
        // In index order, an adaptive plan appends each pass before its result comes up: the
        // passes it planned depend only on the results before them.
        for (const auto& [t, bytes] : *results) {
            absl::StatusOr<TileSums> sums = DecodeTileSums(bytes);
            absl::StatusOr<std::vector<RenderTask>> pass =
                sums.ok() ? job->merger->Merge(t, *sums)
                          : absl::StatusOr<std::vector<RenderTask>>(sums.status());
            // The store wrote what merged before, so this cannot fail unless the file was
            // damaged; the task is then simply rendered again.
            if (!pass.ok()) {
                Log()->warn("job={} task={}: the recorded result is unusable, rendering it again",
                            job->record.id, t);
                continue;
            }
            job->tasks[size_t(t)].state = TaskState::kDone;
            job->tasks.resize(job->merger->tasks().size());
        }
        QueueStart(*job);
        job->record.tasks_done = int(job->merger->tasks_done());
        job->record.tasks_total = int(job->merger->tasks().size());
        job->record.stats = job->merger->stats();
        job->record.tasks_running = 0;
        Log()->info("job={} recovered: {}/{} tasks done, {} leases handed out before",
                    job->record.id, job->record.tasks_done, job->record.tasks_total,
                    job->record.tasks_leased);
        if (EnforceTimeLimit(*job, clock_()) || job->merger->Complete()) {
            rendered.push_back(job->record.id);
        }
        Save(*job);
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

std::optional<TaskAssignment> Scheduler::LeaseTask(const std::string& worker, absl::Time wait_until) {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        if (std::optional<TaskAssignment> lease = TryLease(worker)) return lease;
        const uint64_t version = version_;
        if (shutdown_ || !changed_.wait_until(lock, absl::ToChronoTime(wait_until),
                                              [&] { return version_ != version || shutdown_; })) {
            return std::nullopt;
        }
    }
}

std::optional<TaskAssignment> Scheduler::TryLease(const std::string& worker) {
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
            if (!MayTake(*job, t, worker, now)) continue;
            best = job.get();
            best_task = t;
            break;
        }
    }
    if (best) return Grant(*best, best_task, worker, now);
    for (auto& [id, job] : active_) {
        if (const int t = StragglerFor(*job, worker, now); t >= 0) {
            Log()->info("job={} task={} running for {}: leased again to {}", id, t,
                        absl::FormatDuration(now - job->tasks[size_t(t)].leased_at), worker);
            return Grant(*job, t, worker, now);
        }
    }
    return std::nullopt;
}

int Scheduler::StragglerFor(const Job& job, const std::string& worker, absl::Time now) const {
    if (!job.queued.empty()) return -1;
    absl::Duration limit = options_.speculate_after;
    if (job.tasks_timed > 0) limit = std::max(limit, 2 * job.task_time_total / job.tasks_timed);
    int oldest = -1;
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        const Task& task = job.tasks[size_t(t)];
        if (task.state != TaskState::kLeased || task.live.size() != 1 ||
            task.failed_on.count(worker) ||
            task.holders[size_t(*task.live.begin() - 1)] == worker ||
            now - task.leased_at < limit) {
            continue;
        }
        if (oldest < 0 || task.leased_at < job.tasks[size_t(oldest)].leased_at) oldest = t;
    }
    return oldest;
}

std::string Scheduler::LeaseId(const Job& job, int task, int attempt) const {
    return absl::StrCat(job.record.id, "/", task, "/", boot_, "-", attempt);
}

TaskAssignment Scheduler::Grant(Job& job, int t, const std::string& worker, absl::Time now) {
    Task& task = job.tasks[size_t(t)];
    if (task.state == TaskState::kQueued) {
        job.queued.erase(t);
        task.state = TaskState::kLeased;
        task.leased_at = now;
        ++job.record.tasks_running;
    }
    ++task.attempts;
    task.holders.push_back(worker);
    task.live.insert(task.attempts);
    ++job.record.tasks_leased;
    const std::string lease_id = LeaseId(job, t, task.attempts);
    timeouts_.Set(lease_id, now + options_.lease);
    if (job.record.state == JobState::kQueued) {
        job.record.state = JobState::kRunning;
        job.record.started = now;
    }
    Save(job);
    Log()->debug("job={} task={} leased to {} (attempt {})", job.record.id, t, worker,
                 task.attempts);
    TaskAssignment lease;
    lease.lease_id = lease_id;
    lease.job_id = job.record.id;
    lease.spec = job.record.spec;
    lease.lease = options_.lease;
    lease.heartbeat_interval = options_.heartbeat_interval;
    if (!IsSweepTask(job, t)) {
        lease.task = job.merger->tasks()[size_t(t)];
        lease.radiosity_hash = job.solution;
        return lease;
    }
    const int k = t - int(job.merger->tasks().size()), chunks = job.solve->chunks();
    job.chunk_owner[k % chunks] = worker;
    lease.task.index = t;
    lease.sweep = k / chunks;
    lease.chunk = k % chunks;
    lease.radiosity_hash = job.sweep_input;
    return lease;
}

void Scheduler::QueueStart(Job& job) {
    if (SolvedInSweeps(job.record.spec) && job.solution.empty() && !job.merger->Complete()) {
        // The solve is not recorded: after a restart it runs again, to the same bits, and the
        // tiles already done stay done.
        const RadiositySettings& r = job.record.spec.radiosity;
        job.solve = std::make_unique<RadiositySolve>(r.sweep_tasks, r.tolerance, r.max_iterations);
        job.sweep_input.clear();
        QueueSweep(job);
        return;
    }
    for (int t = 0; t < int(job.merger->tasks().size()); ++t) {
        if (job.tasks[size_t(t)].state == TaskState::kDone) continue;
        if (job.adaptive && !job.adaptive->IsPending(t)) continue;
        job.queued.insert(t);
    }
}

void Scheduler::QueuePass(Job& job, const RenderTask& pass) {
    job.tasks.resize(size_t(pass.index) + 1);
    job.queued.insert(pass.index);
    job.record.tasks_total = int(job.tasks.size());
}

bool Scheduler::EnforceTimeLimit(Job& job, absl::Time now) {
    if (!job.adaptive || job.adaptive->stopped() || job.record.spec.adaptive.time_limit <= 0 ||
        job.record.started == absl::InfinitePast() ||
        now - job.record.started < absl::Seconds(job.record.spec.adaptive.time_limit)) {
        return false;
    }
    const std::vector<int> dropped = job.adaptive->Stop();
    for (int t : dropped) {
        Task& task = job.tasks[size_t(t)];
        for (int attempt : task.live) timeouts_.Remove(LeaseId(job, t, attempt));
        task.live.clear();
        if (task.state == TaskState::kLeased) --job.record.tasks_running;
        job.queued.erase(t);
        task.state = TaskState::kDropped;
    }
    job.record.tasks_total -= int(dropped.size());
    Log()->info("job={} time limit of {} s reached: {} passes dropped, {} tasks merged",
                job.record.id, job.record.spec.adaptive.time_limit, dropped.size(),
                job.merger->tasks_done());
    Save(job);
    // When nothing was dropped, the last result completed the job and Complete said so.
    return !dropped.empty() && job.merger->Complete();
}

std::vector<std::string> Scheduler::EnforceTimeLimits() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> rendered;
    const absl::Time now = clock_();
    for (auto& [id, job] : active_) {
        if (EnforceTimeLimit(*job, now)) rendered.push_back(id);
    }
    return rendered;
}

void Scheduler::QueueSweep(Job& job) {
    for (int c = 0; c < job.solve->chunks(); ++c) {
        job.queued.insert(int(job.tasks.size()));
        job.tasks.emplace_back();
    }
}

bool Scheduler::MayTake(const Job& job, int t, const std::string& worker, absl::Time now) const {
    if (!IsSweepTask(job, t)) return true;
    const auto owner =
        job.chunk_owner.find((t - int(job.merger->tasks().size())) % job.solve->chunks());
    if (owner == job.chunk_owner.end() || owner->second == worker) return true;
    const auto seen = workers_seen_.find(owner->second);
    return seen == workers_seen_.end() || now - seen->second >= options_.lease;
}

std::optional<Scheduler::LeaseRef> Scheduler::Resolve(const std::string& lease_id) {
    const std::vector<std::string> parts = absl::StrSplit(lease_id, '/');
    int task = 0, attempt = 0;
    if (parts.size() != 3 || !absl::SimpleAtoi(parts[1], &task)) return std::nullopt;
    const std::string prefix = boot_ + "-";
    if (parts[2].rfind(prefix, 0) != 0 ||
        !absl::SimpleAtoi(parts[2].substr(prefix.size()), &attempt)) {
        return std::nullopt;
    }
    auto it = active_.find(parts[0]);
    if (it == active_.end() || task < 0 || size_t(task) >= it->second->tasks.size() ||
        attempt < 1 || attempt > it->second->tasks[size_t(task)].attempts) {
        return std::nullopt;
    }
    return LeaseRef{it->second.get(), task, attempt};
}

bool Scheduler::HeldBy(const LeaseRef& ref, const std::string& worker) {
    return ref.job->tasks[size_t(ref.task)].holders[size_t(ref.attempt - 1)] == worker;
}

bool Scheduler::IsCurrent(const LeaseRef& ref) {
    const Task& task = ref.job->tasks[size_t(ref.task)];
    return task.state == TaskState::kLeased && task.live.count(ref.attempt);
}

bool Scheduler::Heartbeat(const std::string& lease_id, const std::string& worker) {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    workers_seen_[worker] = now;
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker) || !IsCurrent(*ref)) return false;
    timeouts_.Set(lease_id, now + options_.lease);
    return true;
}

absl::StatusOr<Scheduler::Completion> Scheduler::Complete(const std::string& lease_id,
                                                          const std::string& worker,
                                                          const TileSums& sums) {
    std::unique_lock<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    const absl::StatusOr<LeaseRef> ref = ResultLease(lease_id, worker, now);
    if (!ref.ok()) return ref.status();
    Job& job = *ref->job;
    Task& task = job.tasks[size_t(ref->task)];
    if (task.state == TaskState::kDone || task.state == TaskState::kDropped) {
        return Completion{job.record.id, false};
    }
    absl::StatusOr<std::vector<RenderTask>> merged =
        IsSweepTask(job, ref->task) ? absl::InvalidArgumentError("a tile result for a sweep task")
                                    : job.merger->Merge(ref->task, sums);
    if (!merged.ok()) return Refuse(*ref, lease_id, worker, merged.status());
    MarkDone(job, ref->task, now);
    for (const RenderTask& pass : *merged) QueuePass(job, pass);
    EnforceTimeLimit(job, now);
    job.record.tasks_done = int(job.merger->tasks_done());
    job.record.stats = job.merger->stats();
    const uint64_t ticket = store_.QueueTaskDone(job.record, ref->task, EncodeTileSums(sums));
    ++version_;
    changed_.notify_all();
    Log()->debug("job={} task={} done by {} ({}/{})", job.record.id, ref->task, worker,
                 job.record.tasks_done, job.record.tasks_total);
    const Completion completion{job.record.id, job.merger->Complete()};
    lock.unlock();
    // The worker hears "done" only once the result is durable.
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        // The merge cannot be taken back, and a job whose results are not all recorded would not
        // survive a restart: it fails here, and the worker hears why.
        lock.lock();
        if (auto it = active_.find(completion.job_id); it != active_.end()) {
            FailJob(*it->second,
                    absl::StrCat("recording the result of task ", ref->task, ": ", s.message()));
        }
        return absl::Status(s.code(), absl::StrCat("job=", completion.job_id, ": ", s.message()));
    }
    return completion;
}

absl::StatusOr<Scheduler::LeaseRef> Scheduler::ResultLease(const std::string& lease_id,
                                                           const std::string& worker,
                                                           absl::Time now) {
    workers_seen_[worker] = now;
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker)) {
        Log()->warn("result for lease {} from {} refused: not a lease it holds", lease_id, worker);
        return absl::FailedPreconditionError(absl::StrCat(
            "lease ", lease_id, " is not one of worker ", worker, " in a running job"));
    }
    return *ref;
}

absl::Status Scheduler::Refuse(const LeaseRef& ref, const std::string& lease_id,
                               const std::string& worker, const absl::Status& why) {
    const std::string error = absl::StrCat("job=", ref.job->record.id, " task=", ref.task, " from ",
                                           worker, ": ", why.message());
    if (IsCurrent(ref)) {
        timeouts_.Remove(lease_id);
        Requeue(ref, absl::StrCat("result refused: ", why.message()), true);
    }
    return absl::InvalidArgumentError(error);
}

void Scheduler::MarkDone(Job& job, int t, absl::Time now) {
    Task& task = job.tasks[size_t(t)];
    if (task.state == TaskState::kLeased) {
        // Whoever else holds a lease of it (a retry or a speculative copy) learns at its next
        // heartbeat.
        for (int attempt : task.live) timeouts_.Remove(LeaseId(job, t, attempt));
        task.live.clear();
        --job.record.tasks_running;
        job.task_time_total += now - task.leased_at;
        ++job.tasks_timed;
    } else {
        job.queued.erase(t);
    }
    task.state = TaskState::kDone;
}

absl::StatusOr<Scheduler::SweepCompletion> Scheduler::CompleteSweep(
    const std::string& lease_id, const std::string& worker, const SweepChunkResult& result) {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    const absl::StatusOr<LeaseRef> ref = ResultLease(lease_id, worker, now);
    if (!ref.ok()) return ref.status();
    Job& job = *ref->job;
    if (job.tasks[size_t(ref->task)].state == TaskState::kDone) {
        return SweepCompletion{job.record.id, std::nullopt};
    }
    const int k = ref->task - int(job.merger->tasks().size());
    absl::Status added =
        !IsSweepTask(job, ref->task) ? absl::InvalidArgumentError("a sweep result for a tile")
        : result.sweep != k / job.solve->chunks() || result.chunk != k % job.solve->chunks()
            ? absl::InvalidArgumentError(
                  absl::StrCat("a result of sweep ", result.sweep, " chunk ", result.chunk))
            : job.solve->Add(result);
    if (!added.ok()) return Refuse(*ref, lease_id, worker, added);
    MarkDone(job, ref->task, now);
    SweepCompletion completion{job.record.id, std::nullopt};
    if (job.solve->SweepComplete()) {
        absl::StatusOr<RadiositySolve::Outcome> outcome = job.solve->FinishSweep();
        if (!outcome.ok()) {
            FailJob(job, std::string(outcome.status().message()));
            return completion;
        }
        Log()->info("job={} radiosity sweep {}: relative residual {:.3g}{}", job.record.id,
                    outcome->iterations, outcome->residual, outcome->converged ? ", solved" : "");
        completion.outcome = std::move(*outcome);
    }
    Save(job);
    return completion;
}

void Scheduler::Publish(const std::string& job_id, bool converged,
                        const absl::StatusOr<std::string>& hash) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return;  // cancelled meanwhile
    Job& job = *it->second;
    if (!hash.ok()) {
        FailJob(job, absl::StrCat("storing the radiosity: ", hash.status().message()));
        return;
    }
    if (converged) {
        job.solution = *hash;
        job.solve.reset();
        QueueStart(job);
    } else {
        job.sweep_input = *hash;
        QueueSweep(job);
    }
    Save(job);
}

absl::Status Scheduler::Fail(const std::string& lease_id, const std::string& worker,
                             const std::string& reason, FailureKind kind) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker) || !IsCurrent(*ref)) return absl::OkStatus();
    timeouts_.Remove(lease_id);
    Requeue(*ref, absl::StrCat(reason, " (worker ", worker, ")"), kind == FailureKind::kTaskError);
    return absl::OkStatus();
}

void Scheduler::Requeue(const LeaseRef& ref, const std::string& reason, bool counted) {
    Job& job = *ref.job;
    const int t = ref.task;
    Task& task = job.tasks[size_t(t)];
    task.live.erase(ref.attempt);
    if (counted) {
        ++task.failures;
        task.failed_on.insert(task.holders[size_t(ref.attempt - 1)]);
    }
    Log()->warn("job={} task={} attempt {} failed: {}{}", job.record.id, t, ref.attempt, reason,
                counted ? "" : " (not counted)");
    if (task.failures >= options_.max_failures) {
        FailJob(job, absl::StrCat("task ", t, " failed ", task.failures, " times; last: ", reason));
        return;
    }
    if (task.live.empty()) {  // otherwise another lease of it is still rendering
        task.state = TaskState::kQueued;
        --job.record.tasks_running;
        job.queued.insert(t);
        ++job.record.retries;
    }
    Save(job);
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
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        for (int attempt : job.tasks[size_t(t)].live) timeouts_.Remove(LeaseId(job, t, attempt));
    }
    if (absl::Status s = store_.WaitDurable(Save(job)); !s.ok()) {
        Log()->error("job={} ended ({}) but not recorded: {}", job.record.id,
                     JobStateName(job.record.state), std::string(s.message()));
        // Readers and watchers still learn how it ended; the store, which says it runs, has it
        // run again after a restart.
        unrecorded_[job.record.id] = job.record;
    }
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
        if (!ref || !IsCurrent(*ref)) continue;
        const std::string& worker =
            ref->job->tasks[size_t(ref->task)].holders[size_t(ref->attempt - 1)];
        Requeue(*ref,
                absl::StrCat("lease expired: worker ", worker, " sent no heartbeat for ",
                             absl::FormatDuration(options_.lease)),
                true);
    }
    return int(expired.size());
}

absl::StatusOr<Scheduler::JobImage> Scheduler::Snapshot(const std::string& job_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) {
        return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
    }
    const Job& job = *it->second;
    JobImage snapshot{job.record, job.merger->Snapshot(), std::nullopt};
    if (job.adaptive) {
        absl::StatusOr<AdaptiveReport> report = job.adaptive->Report();
        if (!report.ok()) return report.status();
        snapshot.adaptive = std::move(*report);
    }
    return snapshot;
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

uint64_t Scheduler::Save(Job& job) {
    const uint64_t ticket = store_.QueuePut(job.record);
    ++version_;
    changed_.notify_all();
    return ticket;
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
