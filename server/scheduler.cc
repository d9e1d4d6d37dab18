#include "server/scheduler.h"

#include <cstdlib>
#include <random>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "lf/core/image_error.h"
#include "lf/core/log.h"
#include "lf/core/tile_codec.h"
#include "lf/job/frame_settings.h"
#include "server/frame_result_codec.h"
#include "server/time_limit.h"

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

absl::Status AlreadyEnded(const JobRecord& record) {
    return absl::FailedPreconditionError(
        absl::StrCat("job ", record.id, " has already ended (", JobStateName(record.state), ")"));
}

}  // namespace

Scheduler::Scheduler(SchedulerOptions options, JobStore& store, Clock clock)
    : options_(options),
      store_(store),
      clock_(std::move(clock)),
      boot_(RandomHex(6)),
      workers_(options.lease) {}

Scheduler::Locked::Locked(Scheduler& scheduler) : lock(scheduler.mutex_), scheduler_(scheduler) {}

Scheduler::Locked::~Locked() {
    if (!lock.owns_lock()) lock.lock();
    if (scheduler_.to_settle_.empty()) return;
    // Taken with the jobs SettleEnded waits for: their tasks are handed on once they are durable
    // (or logged as not recorded), with the lock released for the callback to write.
    std::vector<std::pair<std::string, std::vector<TaskStatus>>> tasks;
    tasks.swap(scheduler_.ended_tasks_);
    SettleEnded();
    lock.unlock();
    if (!scheduler_.tasks_ended_) return;
    for (auto& [id, statuses] : tasks) scheduler_.tasks_ended_(id, std::move(statuses));
}

void Scheduler::Locked::SettleEnded() {
    std::vector<std::pair<std::string, uint64_t>> ended;
    for (const std::string& id : scheduler_.to_settle_) {
        ended.emplace_back(id, scheduler_.ending_.at(id).ticket);
    }
    scheduler_.to_settle_.clear();
    lock.unlock();
    std::vector<absl::Status> durable;
    for (const auto& [id, ticket] : ended) durable.push_back(scheduler_.store_.WaitDurable(ticket));
    lock.lock();
    for (size_t i = 0; i < ended.size(); ++i) {
        auto it = scheduler_.ending_.find(ended[i].first);
        if (!durable[i].ok()) {
            Log()->error("job={} ended ({}) but not recorded: {}", it->first,
                         JobStateName(it->second.record.state), std::string(durable[i].message()));
            // Readers and watchers still learn how it ended; the store, which says it runs, has
            // it run again after a restart.
            scheduler_.unrecorded_[it->first] = std::move(it->second.record);
        }
        scheduler_.ending_.erase(it);
    }
}

void Scheduler::MoveTask(Job& job, int t, TaskState to) {
    if (absl::Status s = job.states.Transition(t, to); !s.ok()) {
        Log()->critical("job={} {}", job.record.id, std::string(s.message()));
        std::abort();
    }
}

void Scheduler::MoveJob(Job& job, JobState to) {
    if (absl::Status s = TransitionJob(job.record, to, clock_()); !s.ok()) {
        Log()->critical("{}", std::string(s.message()));
        std::abort();
    }
}

size_t Scheduler::TaskCount(const Job& job) {
    return job.frame ? job.frame->tasks().size() : job.merger->tasks().size();
}

uint64_t Scheduler::TaskSamples(const Job& job, int task) {
    if (SweepChunkOf(job, task)) return 0;
    const auto samples = [](const auto& t) {
        return uint64_t(t.rect.width) * uint64_t(t.rect.height) * (t.sample_end - t.sample_begin);
    };
    return job.frame ? samples(job.frame->tasks()[size_t(task)])
                     : samples(job.merger->tasks()[size_t(task)]);
}

size_t Scheduler::TasksDone(const Job& job) {
    return job.frame ? job.frame->tasks_done() : job.merger->tasks_done();
}

bool Scheduler::Rendered(const Job& job) {
    return job.frame ? job.frame->Complete() : job.merger->Complete();
}

const RenderStats& Scheduler::StatsOf(const Job& job) {
    return job.frame ? job.frame->stats() : job.merger->stats();
}

void Scheduler::Grow(Job& job, size_t count) {
    job.states.Resize(count);
    job.tasks.resize(count);
}

absl::StatusOr<std::unique_ptr<Scheduler::Job>> Scheduler::NewJob(JobRecord record) const {
    auto job = std::make_unique<Job>();
    job->record = std::move(record);
    // The job's own copy: `record` was moved from, its strings (the method) emptied.
    const JobSpec& spec = job->record.spec;
    job->speculation = SpeculationPolicy(options_.speculate_after);
    if (UsesFramePlan(spec.method)) {
        // The plan local mode makes of the same settings (lf::RenderFrameImage), so the merged
        // sums are its bits; the merger's tiles in the same stores as a tile job's.
        absl::StatusOr<FramePlanSettings> settings = FramePlanSettingsOf(spec.method, spec.plan);
        if (!settings.ok()) return settings.status();
        absl::StatusOr<std::vector<FrameTask>> plan = PlanFrameRender(*settings);
        if (!plan.ok()) return plan.status();
        absl::StatusOr<std::unique_ptr<FrameMerger>> merger =
            FrameMerger::Make(settings->width, settings->height, settings->tile, settings->kind,
                              std::move(*plan), options_.tile_stores);
        if (!merger.ok()) return merger.status();
        job->frame = std::move(*merger);
    } else if (IsAdaptive(spec.adaptive)) {
        absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> plan =
            AdaptiveTilePlan::Make(spec.plan.width, spec.plan.height, spec.plan.spp, spec.plan.tile,
                                   spec.adaptive, kMaxTaskSamples, options_.tile_stores, spec.aovs);
        if (!plan.ok()) return plan.status();
        job->adaptive = plan->get();
        job->merger = std::move(*plan);
    } else {
        absl::StatusOr<std::vector<RenderTask>> plan = PlanRender(spec.plan);
        if (!plan.ok()) return plan.status();
        absl::StatusOr<std::unique_ptr<RenderMerger>> merger = RenderMerger::Make(
            spec.plan.width, spec.plan.height, std::move(*plan), options_.tile_stores, spec.aovs);
        if (!merger.ok()) return merger.status();
        job->merger = std::move(*merger);
    }
    Grow(*job, TaskCount(*job));
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
    job->record.tasks_total = int(TaskCount(*job));
    // The store is read before the lock is taken. An earlier submission it does not hold has not
    // been acknowledged yet, so it is still in memory.
    std::optional<std::string> stored;
    if (!spec.request_id.empty()) {
        absl::StatusOr<std::optional<std::string>> found = store_.FindRequest(spec.request_id);
        if (!found.ok()) return found.status();
        stored = *found;
    }
    std::string id = NewJobId();
    while (store_.Get(id).ok()) id = NewJobId();
    Locked locked(*this);
    std::optional<std::pair<std::string, uint64_t>> earlier =
        stored ? std::pair{*stored, uint64_t(0)} : FindRequestInMemory(spec.request_id);
    if (earlier) {
        locked.lock.unlock();
        if (absl::Status s = store_.WaitDurable(earlier->second); !s.ok()) return s;
        Log()->info("job={} submitted again (request {})", earlier->first,
                    LogSafe(spec.request_id));
        return earlier->first;
    }
    if (active_.size() >= options_.max_active_jobs) {
        return absl::ResourceExhaustedError(
            absl::StrCat(active_.size(),
                         " jobs are queued or running, this server's limit "
                         "(lightfarm-server --max-active-jobs); submit again once some end"));
    }
    // Ids are random: one the store lacks is taken in memory only by a freak.
    while (active_.count(id) || EndedRecord(id)) id = NewJobId();
    job->record.id = id;
    job->record.seq = next_seq_++;
    const uint64_t ticket = Save(*job);
    job->submit_ticket = ticket;
    const size_t job_tasks = job->tasks.size();
    active_[id] = std::move(job);
    locked.lock.unlock();
    // Acknowledged only once durable; waiting outside the lock lets submissions and results
    // share one sync.
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        Log()->error("job={} refused: {}", id, std::string(s.message()));
        locked.lock.lock();
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

std::optional<std::pair<std::string, uint64_t>> Scheduler::FindRequestInMemory(
    const std::string& request_id) const {
    if (request_id.empty()) return std::nullopt;
    for (const auto& [id, job] : active_) {
        if (job->record.spec.request_id == request_id) return std::pair{id, job->submit_ticket};
    }
    for (const auto& [id, ending] : ending_) {
        if (ending.record.spec.request_id == request_id) return std::pair{id, ending.ticket};
    }
    for (const auto& [id, record] : unrecorded_) {
        if (record.spec.request_id == request_id) return std::pair{id, uint64_t(0)};
    }
    return std::nullopt;
}

const JobRecord* Scheduler::EndedRecord(const std::string& job_id) const {
    if (auto it = ending_.find(job_id); it != ending_.end()) return &it->second.record;
    if (auto it = unrecorded_.find(job_id); it != unrecorded_.end()) return &it->second;
    return nullptr;
}

absl::StatusOr<JobRecord> Scheduler::Get(const std::string& job_id) const {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (auto it = active_.find(job_id); it != active_.end()) return it->second->record;
        if (const JobRecord* ended = EndedRecord(job_id)) return *ended;
    }
    return store_.Get(job_id);
}

absl::StatusOr<std::vector<JobRecord>> Scheduler::List(const JobQuery& query) const {
    absl::StatusOr<std::vector<JobRecord>> jobs = store_.List(query);
    if (!jobs.ok()) return jobs.status();
    std::lock_guard<std::mutex> lock(mutex_);
    for (JobRecord& job : *jobs) {
        if (auto it = active_.find(job.id); it != active_.end()) job = it->second->record;
        if (const JobRecord* ended = EndedRecord(job.id)) job = *ended;
    }
    return jobs;
}

std::set<std::string> Scheduler::BlobsInUse() const {
    std::set<std::string> hashes;
    auto add_spec = [&](const JobRecord& record) {
        hashes.insert(record.spec.scene.hash);
        for (const BlobRef& file : record.spec.files) hashes.insert(file.hash);
    };
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, job] : active_) {
        add_spec(job->record);
        for (const std::string* hash : {&job->sweep_input, &job->solution}) {
            if (!hash->empty()) hashes.insert(*hash);
        }
    }
    for (const auto& [id, ending] : ending_) add_spec(ending.record);
    for (const auto& [id, record] : unrecorded_) add_spec(record);
    return hashes;
}

std::optional<std::vector<TaskStatus>> Scheduler::Tasks(const std::string& job_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return std::nullopt;
    return TaskStatuses(*it->second, clock_());
}

std::vector<TaskStatus> Scheduler::TaskStatuses(const Job& job, absl::Time now) const {
    std::vector<TaskStatus> statuses(job.tasks.size());
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        const Task& task = job.tasks[size_t(t)];
        TaskStatus& status = statuses[size_t(t)];
        status.index = t;
        switch (job.states.state(t)) {
            case TaskState::kWaiting:
                status.state = TaskStatus::State::kWaiting;
                break;
            case TaskState::kQueued:
                status.state = TaskStatus::State::kQueued;
                break;
            case TaskState::kLeased:
                status.state = TaskStatus::State::kRunning;
                break;
            case TaskState::kDone:
                status.state = TaskStatus::State::kDone;
                break;
            case TaskState::kDropped:
                status.state = TaskStatus::State::kDropped;
                break;
        }
        PixelRect rect;
        if (job.frame) {
            const FrameTask& frame = job.frame->tasks()[size_t(t)];
            status.kind = TaskKind::kFrame;
            // A light-path task has no camera part: it covers the frame.
            rect = frame.rect.width > 0
                       ? frame.rect
                       : PixelRect{0, 0, job.record.spec.plan.width, job.record.spec.plan.height};
            status.samples = frame.sample_end - frame.sample_begin;
        } else if (SweepChunkOf(job, t)) {
            status.kind = TaskKind::kRadiositySweep;
        } else {
            const RenderTask& tile = job.merger->tasks()[size_t(t)];
            status.kind = TaskKind::kTile;
            rect = tile.rect;
            status.samples = tile.sample_end - tile.sample_begin;
        }
        status.x = rect.x0;
        status.y = rect.y0;
        status.width = rect.width;
        status.height = rect.height;
        status.attempts = task.attempts;
        status.failures = task.failures;
        status.last_error = task.last_error;
        if (task.attempts == 0) continue;  // never leased: no holder, no times
        status.worker = task.holders.back();
        status.leased = task.leased_at;
        status.finished = task.finished;
        if (status.state == TaskStatus::State::kDone) {
            status.duration = task.finished - task.leased_at;
        } else if (status.state == TaskStatus::State::kRunning) {
            status.duration = now - task.leased_at;
        }
    }
    // An ended job's tasks that were not done never will be: its failing task included, whose
    // last failure ended the job before it went back to the queue.
    if (IsFinal(job.record.state)) {
        for (TaskStatus& status : statuses) {
            if (status.state != TaskStatus::State::kDone)
                status.state = TaskStatus::State::kDropped;
        }
    }
    return statuses;
}

std::optional<Scheduler::LeaseHolder> Scheduler::HolderOf(const std::string& lease_id,
                                                          const std::string& worker) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker)) return std::nullopt;
    return LeaseHolder{ref->job->record.id, ref->task, ref->attempt, worker};
}

size_t Scheduler::workers_tracked() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return workers_.size();
}

std::map<std::string, Scheduler::LeaseRef> Scheduler::LeasesByWorker() {
    std::map<std::string, LeaseRef> held;
    // The deadlines are kept for current leases only: fewer than the tasks of running jobs.
    for (const std::string& lease_id : timeouts_.lease_ids()) {
        const std::optional<LeaseRef> ref = Resolve(lease_id);
        if (!ref || !IsCurrent(*ref)) continue;
        const std::string& worker =
            ref->job->tasks[size_t(ref->task)].holders[size_t(ref->attempt - 1)];
        auto [it, added] = held.emplace(worker, *ref);
        if (!added && it->second.attempt < ref->attempt) it->second = *ref;
    }
    return held;
}

std::vector<WorkerStatus> Scheduler::Workers() {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    workers_.ForgetSilent(now);
    const std::map<std::string, LeaseRef> held = LeasesByWorker();
    std::vector<WorkerStatus> workers;
    for (WorkerRegistry::Entry& entry : workers_.List()) {
        WorkerStatus& w = workers.emplace_back();
        w.id = std::move(entry.id);
        w.name = std::move(entry.about.name);
        w.address = std::move(entry.about.address);
        w.version = std::move(entry.about.version);
        w.since_seen = now - entry.last_seen;
        if (auto it = held.find(w.id); it != held.end()) {
            w.job_id = it->second.job->record.id;
            w.task = it->second.task;
        }
    }
    return workers;
}

SchedulerLoad Scheduler::Load() {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    workers_.ForgetSilent(now);
    SchedulerLoad load;
    for (const auto& [id, job] : active_) {
        ++(job->record.state == JobState::kQueued ? load.jobs_queued : load.jobs_running);
        load.tasks_queued += job->states.count(TaskState::kQueued);
        load.tasks_running += job->states.running();
    }
    load.workers_live = int(workers_.size());
    for (const auto& [worker, ref] : LeasesByWorker()) {
        load.workers_busy += workers_.IsLive(worker, now);
    }
    return load;
}

absl::StatusOr<std::vector<std::string>> Scheduler::Recover() {
    // The store is read before the lock is taken.
    struct Stored {
        JobRecord record;
        std::map<int, std::string> results;
    };
    std::vector<Stored> stored;
    uint64_t last_seq = 0;
    // A store that cannot list must not start an empty server.
    absl::StatusOr<std::vector<JobRecord>> recorded = store_.List();
    if (!recorded.ok()) return recorded.status();
    for (JobRecord& record : *recorded) {
        last_seq = std::max(last_seq, record.seq);
        if (IsFinal(record.state)) continue;
        absl::StatusOr<std::map<int, std::string>> results = store_.TaskResults(record.id);
        if (!results.ok()) return results.status();
        stored.push_back({std::move(record), std::move(*results)});
    }
    Locked locked(*this);
    next_seq_ = std::max(next_seq_, last_seq + 1);
    std::vector<std::string> rendered;
    for (Stored& s : stored) {
        if (active_.count(s.record.id)) continue;
        absl::StatusOr<std::unique_ptr<Job>> made = NewJob(std::move(s.record));
        if (!made.ok()) return made.status();
        std::unique_ptr<Job> job = std::move(*made);
        // In index order, an adaptive plan appends each pass before its result comes up: the
        // passes it planned depend only on the results before them.
        for (const auto& [t, bytes] : s.results) {
            absl::Status merged;
            if (job->frame) {
                absl::StatusOr<FrameResult> result = DecodeFrameResult(bytes);
                merged = result.ok() ? job->frame->Add(t, result->camera, result->splats)
                                     : result.status();
            } else {
                absl::StatusOr<TileSums> sums = DecodeTileSums(bytes);
                absl::StatusOr<std::vector<RenderTask>> pass =
                    sums.ok() ? job->merger->Merge(t, *sums)
                              : absl::StatusOr<std::vector<RenderTask>>(sums.status());
                merged = pass.status();
            }
            // The store wrote what merged before, so this cannot fail unless the file was
            // damaged; the task is then simply rendered again.
            if (!merged.ok()) {
                Log()->warn("job={} task={}: the recorded result is unusable, rendering it again",
                            job->record.id, t);
                continue;
            }
            MoveTask(*job, t, TaskState::kDone);
            Grow(*job, TaskCount(*job));
        }
        QueueStart(*job);
        job->record.tasks_done = int(TasksDone(*job));
        job->record.tasks_total = int(TaskCount(*job));
        job->record.stats = StatsOf(*job);
        Log()->info("job={} recovered: {}/{} tasks done, {} leases handed out before",
                    job->record.id, job->record.tasks_done, job->record.tasks_total,
                    job->record.tasks_leased);
        if (EnforceTimeLimit(*job, clock_()) || Rendered(*job)) {
            rendered.push_back(job->record.id);
        }
        Save(*job);
        active_[job->record.id] = std::move(job);
    }
    return rendered;
}

std::optional<TaskAssignment> Scheduler::LeaseTask(const std::string& worker, absl::Time wait_until,
                                                   const WorkerDescription* about) {
    Locked locked(*this);
    while (true) {
        if (std::optional<TaskAssignment> lease = TryLease(worker, about)) return lease;
        const uint64_t version = version_;
        if (shutdown_ || !changed_.wait_until(locked.lock, absl::ToChronoTime(wait_until),
                                              [&] { return version_ != version || shutdown_; })) {
            return std::nullopt;
        }
    }
}

std::optional<TaskAssignment> Scheduler::TryLease(const std::string& worker,
                                                  const WorkerDescription* about) {
    const absl::Time now = clock_();
    workers_.Seen(worker, now, about);
    workers_.ForgetSilent(now);  // so that the workers kept are the live ones
    Job* best = nullptr;
    int best_task = -1;
    for (auto& [id, job] : active_) {
        if (best && (job->record.spec.priority < best->record.spec.priority ||
                     (job->record.spec.priority == best->record.spec.priority &&
                      job->record.seq > best->record.seq))) {
            continue;
        }
        for (int t : job->states.queued()) {
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
                        absl::FormatDuration(now - job->tasks[size_t(t)].leased_at),
                        LogSafe(worker));
            return Grant(*job, t, worker, now);
        }
    }
    return std::nullopt;
}

int Scheduler::StragglerFor(const Job& job, const std::string& worker, absl::Time now) const {
    if (!job.states.queued().empty()) return -1;
    int oldest = -1;
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        const Task& task = job.tasks[size_t(t)];
        if (job.states.state(t) != TaskState::kLeased || task.live.size() != 1 ||
            task.failed_on.count(worker) ||
            task.holders[size_t(*task.live.begin() - 1)] == worker ||
            !job.speculation.IsStraggler(now - task.leased_at)) {
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
    if (job.states.state(t) == TaskState::kQueued) {
        MoveTask(job, t, TaskState::kLeased);
        task.leased_at = now;
    }
    ++task.attempts;
    task.holders.push_back(worker);
    task.live.insert(task.attempts);
    ++job.record.tasks_leased;
    metrics_.leases.Add();
    const std::string lease_id = LeaseId(job, t, task.attempts);
    timeouts_.Set(lease_id, now + options_.lease);
    if (job.record.state == JobState::kQueued) MoveJob(job, JobState::kRunning);
    Save(job);
    Log()->debug("job={} task={} leased to {} (attempt {})", job.record.id, t, LogSafe(worker),
                 task.attempts);
    TaskAssignment lease;
    lease.lease_id = lease_id;
    lease.job_id = job.record.id;
    lease.spec = job.record.spec;
    lease.lease = options_.lease;
    lease.heartbeat_interval = options_.heartbeat_interval;
    const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(job, t);
    if (job.frame) {
        const FrameTask& frame = job.frame->tasks()[size_t(t)];
        lease.task = RenderTask{frame.index, frame.rect, frame.sample_begin, frame.sample_end};
        lease.path_begin = frame.path_begin;
        lease.path_end = frame.path_end;
        return lease;
    }
    if (!at) {
        lease.task = job.merger->tasks()[size_t(t)];
        lease.radiosity_hash = job.solution;
        return lease;
    }
    job.chunk_owner[at->chunk] = worker;
    lease.task.index = t;
    lease.sweep = at->sweep;
    lease.chunk = at->chunk;
    lease.radiosity_hash = job.sweep_input;
    return lease;
}

void Scheduler::QueueStart(Job& job) {
    if (SolvedInSweeps(job.record.spec) && job.solution.empty() && !job.merger->Complete()) {
        // The solve is not recorded: after a restart it runs again, to the same bits, and the
        // tiles already done stay done.
        const RadiositySettings& r = job.record.spec.radiosity;
        job.solve = std::make_unique<RadiositySolve>(r.sweep_tasks, r.tolerance, r.max_iterations);
        job.sweeps = SweepTaskNumbering{int(job.merger->tasks().size()), job.solve->chunks()};
        job.sweep_input.clear();
        QueueSweep(job);
        return;
    }
    for (int t = 0; t < int(TaskCount(job)); ++t) {
        if (job.states.state(t) != TaskState::kWaiting) continue;
        if (job.adaptive && !job.adaptive->IsPending(t)) continue;
        MoveTask(job, t, TaskState::kQueued);
    }
}

void Scheduler::QueueSweep(Job& job) {
    const int sweep = job.solve->sweep();
    Grow(job, size_t(job.sweeps->ToIndex({sweep + 1, 0})));
    for (int c = 0; c < job.sweeps->chunks; ++c) {
        MoveTask(job, job.sweeps->ToIndex({sweep, c}), TaskState::kQueued);
    }
}

void Scheduler::QueuePass(Job& job, const RenderTask& pass) {
    Grow(job, size_t(pass.index) + 1);
    MoveTask(job, pass.index, TaskState::kQueued);
    job.record.tasks_total = int(job.tasks.size());
}

bool Scheduler::EnforceTimeLimit(Job& job, absl::Time now) {
    if (!job.adaptive || job.adaptive->stopped() ||
        !TimeLimitReached(job.record.spec.adaptive, job.record.started, now)) {
        return false;
    }
    const std::vector<int> dropped = job.adaptive->Stop();
    for (int t : dropped) {
        Task& task = job.tasks[size_t(t)];
        for (int attempt : task.live) timeouts_.Remove(LeaseId(job, t, attempt));
        task.live.clear();
        MoveTask(job, t, TaskState::kDropped);
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
    Locked locked(*this);
    std::vector<std::string> rendered;
    const absl::Time now = clock_();
    for (auto& [id, job] : active_) {
        if (EnforceTimeLimit(*job, now)) rendered.push_back(id);
    }
    return rendered;
}

std::optional<SweepTaskNumbering::SweepChunk> Scheduler::SweepChunkOf(const Job& job, int t) {
    return job.sweeps ? job.sweeps->FromIndex(t) : std::nullopt;
}

bool Scheduler::MayTake(const Job& job, int t, const std::string& worker, absl::Time now) const {
    if (const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(job, t)) {
        const auto owner = job.chunk_owner.find(at->chunk);
        if (owner != job.chunk_owner.end() && owner->second != worker &&
            workers_.IsLive(owner->second, now)) {
            return false;
        }
    }
    const Task& task = job.tasks[size_t(t)];
    if (!task.failed_on.count(worker)) return true;
    // It failed here: it waits for a live worker it has not failed on. Once it has failed on
    // every live worker it is tried again anywhere, so its failures end the job. `failed_on`
    // holds fewer than max_failures workers, and the workers kept are the live ones.
    size_t live_failed = 0;
    for (const std::string& w : task.failed_on) live_failed += workers_.IsLive(w, now);
    return workers_.size() <= live_failed;
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
    return ref.job->states.state(ref.task) == TaskState::kLeased && task.live.count(ref.attempt);
}

bool Scheduler::Heartbeat(const std::string& lease_id, const std::string& worker) {
    Locked locked(*this);
    const absl::Time now = clock_();
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker)) return false;  // a made-up id is not kept
    workers_.Seen(worker, now);
    if (!IsCurrent(*ref)) return false;
    timeouts_.Set(lease_id, now + options_.lease);
    return true;
}

absl::StatusOr<Scheduler::Completion> Scheduler::Complete(const std::string& lease_id,
                                                          const std::string& worker,
                                                          const TileSums& sums, SplatList* splats) {
    Locked locked(*this);
    const absl::Time now = clock_();
    const absl::StatusOr<LeaseRef> ref = ResultLease(lease_id, worker, now);
    if (!ref.ok()) return ref.status();
    Job& job = *ref->job;
    const TaskState state = job.states.state(ref->task);
    if (state == TaskState::kDone || state == TaskState::kDropped) {
        return Completion{job.record.id, false};
    }
    absl::StatusOr<std::vector<RenderTask>> merged = std::vector<RenderTask>{};
    if (SweepChunkOf(job, ref->task)) {
        merged = absl::InvalidArgumentError("a tile result for a sweep task");
    } else if (job.frame) {
        // Frame plans are fixed: a merge appends no task.
        const absl::Status added =
            !splats ? absl::InvalidArgumentError("a frame task's result without its splats")
                    : job.frame->Add(ref->task, sums, *splats);
        if (!added.ok()) merged = added;
    } else if (splats) {
        merged = absl::InvalidArgumentError("splats in the result of a tile task");
    } else {
        merged = job.merger->Merge(ref->task, sums);
    }
    if (!merged.ok()) return Refuse(*ref, lease_id, worker, merged.status());
    MarkDone(job, ref->task, now);
    for (const RenderTask& pass : *merged) QueuePass(job, pass);
    EnforceTimeLimit(job, now);
    job.record.tasks_done = int(TasksDone(job));
    job.record.stats = StatsOf(job);
    job.record.tasks_running = job.states.running();
    // A frame task's record holds its splats too, so that a restart merges the same sums.
    const uint64_t ticket = store_.QueueTaskDone(
        job.record, ref->task, job.frame ? EncodeFrameResult(sums, *splats) : EncodeTileSums(sums));
    ++version_;
    changed_.notify_all();
    Log()->debug("job={} task={} done by {} ({}/{})", job.record.id, ref->task, LogSafe(worker),
                 job.record.tasks_done, job.record.tasks_total);
    const Completion completion{job.record.id, Rendered(job)};
    locked.lock.unlock();
    // The worker hears "done" only once the result is durable.
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        // The merge cannot be taken back, and a job whose results are not all recorded would not
        // survive a restart: it fails here, and the worker hears why.
        locked.lock.lock();
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
    const std::optional<LeaseRef> ref = Resolve(lease_id);
    if (!ref || !HeldBy(*ref, worker)) {
        Log()->warn("result for lease {} from {} refused: not a lease it holds", LogSafe(lease_id),
                    LogSafe(worker));
        return absl::FailedPreconditionError(absl::StrCat(
            "lease ", lease_id, " is not one of worker ", worker, " in a running job"));
    }
    workers_.Seen(worker, now);
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
    task.finished = now;
    if (job.states.state(t) == TaskState::kLeased) {
        // Whoever else holds a lease of it (a retry or a speculative copy) learns at its next
        // heartbeat.
        for (int attempt : task.live) timeouts_.Remove(LeaseId(job, t, attempt));
        task.live.clear();
        job.speculation.TaskDone(now - task.leased_at);
        metrics_.task_seconds.Observe(absl::ToDoubleSeconds(now - task.leased_at));
    }
    MoveTask(job, t, TaskState::kDone);
    metrics_.tasks_done.Add(now, 1);
    metrics_.samples_done.Add(now, TaskSamples(job, t));
}

absl::StatusOr<Scheduler::SweepCompletion> Scheduler::CompleteSweep(
    const std::string& lease_id, const std::string& worker, const SweepChunkResult& result) {
    Locked locked(*this);
    const absl::Time now = clock_();
    const absl::StatusOr<LeaseRef> ref = ResultLease(lease_id, worker, now);
    if (!ref.ok()) return ref.status();
    Job& job = *ref->job;
    if (job.states.state(ref->task) == TaskState::kDone) {
        return SweepCompletion{job.record.id, std::nullopt};
    }
    const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(job, ref->task);
    const SweepTaskNumbering::SweepChunk got{result.sweep, result.chunk};
    absl::Status added = !at ? absl::InvalidArgumentError("a sweep result for a tile")
                         : *at != got
                             ? absl::InvalidArgumentError(absl::StrCat(
                                   "a result of sweep ", result.sweep, " chunk ", result.chunk))
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
    Locked locked(*this);
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
    Locked locked(*this);
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
        metrics_.task_failures.Add();
        ++task.failures;
        task.failed_on.insert(task.holders[size_t(ref.attempt - 1)]);
        task.last_error = reason;
        job.record.last_error = absl::StrCat("task ", t, ": ", reason);
    }
    Log()->warn("job={} task={} attempt {} failed: {}{}", job.record.id, t, ref.attempt,
                LogSafe(reason), counted ? "" : " (not counted)");
    if (task.failures >= options_.max_failures) {
        FailJob(job, absl::StrCat("task ", t, " failed ", task.failures, " times; last: ", reason));
        return;
    }
    if (task.live.empty()) {  // otherwise another lease of it is still rendering
        MoveTask(job, t, TaskState::kQueued);
        ++job.record.retries;
    }
    Save(job);
}

void Scheduler::FailJob(Job& job, const std::string& error) {
    MoveJob(job, JobState::kFailed);
    job.record.error = error;
    Log()->error("job={} failed: {}", job.record.id, LogSafe(error));
    EndJob(job);
}

JobRecord Scheduler::EndJob(Job& job) {
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        for (int attempt : job.tasks[size_t(t)].live) timeouts_.Remove(LeaseId(job, t, attempt));
    }
    const std::string id = job.record.id;
    ended_tasks_.emplace_back(id, TaskStatuses(job, clock_()));
    const uint64_t ticket = Save(job);
    ending_[id] = Ending{job.record, ticket};
    to_settle_.push_back(id);
    active_.erase(id);  // destroys `job`
    return ending_[id].record;
}

absl::StatusOr<JobRecord> Scheduler::Cancel(const std::string& job_id) {
    std::optional<JobRecord> cancelled;
    {
        Locked locked(*this);
        if (auto it = active_.find(job_id); it != active_.end()) {
            MoveJob(*it->second, JobState::kCancelled);
            cancelled = EndJob(*it->second);
            Log()->info("job={} cancelled", job_id);
        } else if (const JobRecord* ended = EndedRecord(job_id)) {
            return AlreadyEnded(*ended);
        }
    }  // the cancellation is durable here, or logged as not recorded
    if (cancelled) return *cancelled;
    absl::StatusOr<JobRecord> record = store_.Get(job_id);
    if (!record.ok()) return record.status();
    return AlreadyEnded(*record);
}

absl::StatusOr<JobRecord> Scheduler::SetPriority(const std::string& job_id, int priority) {
    JobRecord record;
    uint64_t ticket = 0;
    {
        Locked locked(*this);
        auto it = active_.find(job_id);
        if (it == active_.end()) {
            if (const JobRecord* ended = EndedRecord(job_id)) return AlreadyEnded(*ended);
            locked.lock.unlock();  // the store is never read under the lock
            absl::StatusOr<JobRecord> stored = store_.Get(job_id);
            if (!stored.ok()) return stored.status();
            return AlreadyEnded(*stored);
        }
        Job& job = *it->second;
        Log()->info("job={} priority {} -> {}", job_id, job.record.spec.priority, priority);
        job.record.spec.priority = priority;
        ticket = Save(job);
        record = job.record;
    }
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) return s;
    return record;
}

int Scheduler::ExpireLeases() {
    Locked locked(*this);
    const absl::Time now = clock_();
    workers_.ForgetSilent(now);
    const std::vector<std::string> expired = timeouts_.TakeExpired(now);
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
    JobImage snapshot;
    std::shared_ptr<const TileStore> tiles;            // outlives the job if it ends meanwhile
    std::optional<FrameMerger::SnapshotSource> frame;  // a frame job's stores, the same
    {
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = active_.find(job_id);
        if (it == active_.end()) {
            return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
        }
        const Job& job = *it->second;
        snapshot.record = job.record;
        if (job.frame) {
            // Read after the lock is released, as a tile job's store: a preview may show a tile
            // merged meanwhile with the normalisation before it; a complete job's is exact.
            frame = job.frame->snapshot_source();
        } else {
            tiles = job.merger->store();
        }
        if (job.adaptive) snapshot.adaptive = job.adaptive->TileReport();
    }
    const RenderPlanSettings& plan = snapshot.record.spec.plan;
    absl::StatusOr<Image> image =
        frame ? frame->Read() : RenderImageOf(*tiles, plan.width, plan.height);
    if (!image.ok()) return image.status();
    snapshot.image = std::move(*image);
    if (snapshot.adaptive) {
        absl::StatusOr<double> estimated = EstimatedRelativeError(snapshot.image);
        if (!estimated.ok()) return estimated.status();
        snapshot.adaptive->estimated_error = *estimated;
    }
    return snapshot;
}

void Scheduler::Finish(const std::string& job_id, const absl::StatusOr<std::string>& result_path) {
    Locked locked(*this);
    auto it = active_.find(job_id);
    if (it == active_.end()) return;  // cancelled meanwhile
    Job& job = *it->second;
    if (!result_path.ok()) {
        FailJob(job, absl::StrCat("writing the result: ", result_path.status().message()));
        return;
    }
    MoveJob(job, JobState::kSucceeded);
    job.record.result_path = *result_path;
    Log()->info("job={} succeeded: {} samples -> {}", job_id, job.record.stats.samples,
                *result_path);
    EndJob(job);
}

uint64_t Scheduler::Save(Job& job) {
    // Derived, so that the record cannot disagree with the task states.
    job.record.tasks_running = IsFinal(job.record.state) ? 0 : job.states.running();
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
