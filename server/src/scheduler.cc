#include "lf/server/scheduler.h"

#include <algorithm>
#include <cstdlib>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/image_error.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/job/worker_tags.h"
#include "lf/server/blocklist.h"

namespace lf {

namespace {

// The key of a token's strikes as a whole (WorkerRegistry::Abandoned), apart from its workers'
// (TOKEN/claimed-id, which always hold a '/'); empty for workers without a token.
std::string TokenStrikes(const std::string& worker) {
    const std::string principal = PrincipalOf(worker);
    return principal.empty() ? "" : "token " + principal;
}

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("scheduler"); }

std::string NewJobId() { return "job-" + RandomHex(10); }

absl::Status AlreadyEnded(const JobRecord& record) {
    return absl::FailedPreconditionError(
        absl::StrCat("job ", record.id, " has already ended (", JobStateName(record.state), ")"));
}

// Unavailable for a job whose final record is not durable yet.
absl::Status JustEnded(const std::string& job_id) {
    return absl::UnavailableError(absl::StrCat(
        "job ", job_id,
        " has just ended and its record is not in the store yet; requeue it again in a moment"));
}

// `requeue --frames`: InvalidArgument for a still or frames outside the shot, naming them;
// FailedPrecondition for an adaptive shot (its passes take task indices in the order they merged,
// so some frames' results cannot be dropped and the rest merged again as recorded).
absl::Status CheckRequeuedFrames(const JobRecord& job, const FrameRange& frames) {
    const std::string what = absl::StrCat("--frames ", FrameRangeText(frames), ": ");
    const std::optional<FrameRange>& shot = job.spec.shot.frames;
    if (!shot) {
        return absl::InvalidArgumentError(absl::StrCat(
            what, "job ", job.id, " is a still image; --frames applies to a shot's frames"));
    }
    std::vector<int> outside;
    for (int i = 0; i < frames.count(); ++i) {
        if (!shot->Contains(frames.at(i))) outside.push_back(frames.at(i));
    }
    if (!outside.empty()) {
        constexpr size_t kNamed = 10;
        const std::string named = outside.size() == 1 ? "frame " : "frames ";
        const std::string more =
            outside.size() > kNamed ? absl::StrCat(" and ", outside.size() - kNamed, " more") : "";
        outside.resize(std::min(outside.size(), kNamed));
        return absl::InvalidArgumentError(absl::StrCat(what, named, absl::StrJoin(outside, ", "),
                                                       more, " not in job ", job.id, "'s shot (",
                                                       FrameRangeText(*shot), ")"));
    }
    if (IsAdaptive(job.spec.adaptive)) {
        return absl::FailedPreconditionError(
            absl::StrCat(what, "job ", job.id,
                         " samples adaptively: its frames cannot be rendered again alone"));
    }
    return absl::OkStatus();
}

}  // namespace

Scheduler::Scheduler(SchedulerOptions options, JobStore& store, Clock clock)
    : options_(options),
      store_(store),
      clock_(std::move(clock)),
      workers_(options.lease, options.forget_workers_after) {}

Scheduler::Locked::Locked(Scheduler& scheduler) : lock(scheduler.mutex_), scheduler_(scheduler) {}

Scheduler::Locked::~Locked() {
    if (!lock.owns_lock()) lock.lock();
    if (!scheduler_.ended_.has_unsettled()) return;
    SettleEnded();
}

void Scheduler::Locked::SettleEnded() {
    // Taken with the jobs whose ends settle here: their tasks are handed on once their records
    // are durable (or logged as not recorded), with the lock released for the callback to write,
    // and before the ends settle, so a client told of an end lists the job's tasks at once.
    std::vector<std::pair<JobRecord, std::vector<TaskStatus>>> tasks;
    tasks.swap(scheduler_.ended_tasks_);
    const std::vector<std::pair<std::string, uint64_t>> ended = scheduler_.ended_.TakeUnsettled();
    lock.unlock();
    std::vector<absl::Status> durable;
    for (const auto& [id, ticket] : ended) durable.push_back(scheduler_.store_.WaitDurable(ticket));
    if (scheduler_.tasks_ended_) {
        for (auto& [record, statuses] : tasks) scheduler_.tasks_ended_(record, std::move(statuses));
    }
    lock.lock();
    for (size_t i = 0; i < ended.size(); ++i) scheduler_.ended_.Settle(ended[i].first, durable[i]);
    scheduler_.left_memory_ += ended.size();
    // A change: a WaitForChange begun after the end's Save returns for its settling too.
    ++scheduler_.version_;
    scheduler_.changed_.notify_all();
    scheduler_.settled_.notify_all();
}

absl::StatusOr<std::string> Scheduler::Submit(const JobSpec& spec) {
    JobRecord record;
    record.spec = spec;
    absl::StatusOr<std::vector<std::string>> after = CheckDependencyIds(spec.after, "after");
    if (!after.ok()) return after.status();
    record.spec.after = std::move(*after);
    absl::StatusOr<std::unique_ptr<Job>> made =
        Job::Make(std::move(record), options_.tile_stores, options_.speculate_after);
    if (!made.ok()) return made.status();
    std::unique_ptr<Job> job = std::move(*made);
    job->Queue(job->execution->Start());
    job->record.submitted = clock_();
    std::string id = NewJobId();
    while (store_.Get(id).ok()) id = NewJobId();
    Locked locked(*this);
    absl::StatusOr<std::optional<std::pair<std::string, uint64_t>>> earlier =
        FindRequest(spec.request_id, locked);
    if (!earlier.ok()) return earlier.status();
    // Read after the request: no dependency of a retried submission is checked again.
    if (!*earlier && !job->record.spec.after.empty()) {
        absl::StatusOr<std::map<std::string, DependencyState>> states =
            DependencyStates(job->record.spec.after, locked);
        if (!states.ok()) return states.status();
        for (const auto& [dep, state] : *states) {
            if (absl::Status s = CheckNewDependency(state); !s.ok()) return s;
        }
        // The store was read without the lock: the same request may have come in meanwhile.
        *earlier = FindRequestInMemory(spec.request_id);
    }
    if (*earlier) {
        locked.lock.unlock();
        if (absl::Status s = store_.WaitDurable((*earlier)->second); !s.ok()) return s;
        Log()->info("job={} submitted again (request {})", (*earlier)->first,
                    LogSafe(spec.request_id));
        return (*earlier)->first;
    }
    if (absl::Status s = CheckActiveJobLimit("submit"); !s.ok()) return s;
    // Ids are random: one the store lacks is taken in memory only by a freak.
    while (active_.count(id) || ended_.Find(id)) id = NewJobId();
    job->record.id = id;
    job->record.seq = next_seq_++;
    const uint64_t ticket = Save(*job);
    job->submit_ticket = ticket;
    job->run = next_run_++;
    const std::string summary = job->execution->Summary();
    active_[id] = std::move(job);
    locked.lock.unlock();
    // Acknowledged only once durable; waiting outside the lock lets submissions and results
    // share one sync.
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        Log()->error("job={} refused: {}", id, std::string(s.message()));
        locked.lock.lock();
        leases_.ForgetJob(id);  // a worker may have leased one of its tasks meanwhile
        active_.erase(id);
        return s;
    }
    Log()->info("job={} queued: {}, priority {}", id, summary, spec.priority);
    return id;
}

absl::Status Scheduler::CheckActiveJobLimit(const char* action) const {
    if (active_.size() < options_.max_active_jobs) return absl::OkStatus();
    return absl::ResourceExhaustedError(absl::StrCat(
        active_.size(),
        " jobs are queued or running, this server's limit (lightfarm-server --max-active-jobs); ",
        action, " again once some end"));
}

absl::StatusOr<std::optional<std::pair<std::string, uint64_t>>> Scheduler::FindRequest(
    const std::string& request_id, Locked& locked) {
    if (request_id.empty()) return std::nullopt;
    while (true) {
        // The store is read without the lock. An earlier submission it does not hold has not
        // been acknowledged yet, so it is in memory after the read, unless it ended and left
        // memory for the store during the read: then the store is read again.
        const uint64_t left_before = left_memory_;
        locked.lock.unlock();
        absl::StatusOr<std::optional<std::string>> stored = store_.FindRequest(request_id);
        locked.lock.lock();
        if (!stored.ok()) return stored.status();
        if (*stored) return std::pair{**stored, uint64_t(0)};
        if (auto in_memory = FindRequestInMemory(request_id)) return in_memory;
        if (left_memory_ == left_before) return std::nullopt;
    }
}

std::optional<std::pair<std::string, uint64_t>> Scheduler::FindRequestInMemory(
    const std::string& request_id) const {
    if (request_id.empty()) return std::nullopt;
    for (const auto& [id, job] : active_) {
        if (job->record.spec.request_id == request_id) return std::pair{id, job->submit_ticket};
    }
    return ended_.FindRequest(request_id);
}

absl::StatusOr<JobRecord> Scheduler::Get(const std::string& job_id) const {
    absl::StatusOr<std::optional<JobRecord>> job = Read(job_id, false);
    if (!job.ok()) return job.status();
    return std::move(**job);
}

absl::StatusOr<std::optional<JobRecord>> Scheduler::GetSettled(const std::string& job_id) const {
    return Read(job_id, true);
}

absl::StatusOr<std::optional<JobRecord>> Scheduler::Read(const std::string& job_id,
                                                         bool settled_only) const {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (auto it = active_.find(job_id); it != active_.end()) {
            return ReadRecord(*it->second, clock_());
        }
        if (settled_only && ended_.IsSettling(job_id)) return std::nullopt;
        if (const JobRecord* ended = ended_.Find(job_id)) return *ended;
    }
    absl::StatusOr<JobRecord> stored = store_.Get(job_id);
    if (!stored.ok()) return stored.status();
    return std::move(*stored);
}

absl::StatusOr<std::vector<JobRecord>> Scheduler::List(const JobQuery& query) const {
    absl::StatusOr<std::vector<JobRecord>> jobs = store_.List(query);
    if (!jobs.ok()) return jobs.status();
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    for (JobRecord& job : *jobs) {
        if (auto it = active_.find(job.id); it != active_.end()) job = ReadRecord(*it->second, now);
        if (const JobRecord* ended = ended_.Find(job.id)) job = *ended;
    }
    return jobs;
}

std::set<std::string> Scheduler::BlobsInUse() const {
    std::set<std::string> hashes;
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, job] : active_) {
        hashes.insert(job->record.spec.scene.hash);
        for (const BlobRef& file : job->record.spec.files) hashes.insert(file.hash);
        job->execution->AddBlobsInUse(hashes);
    }
    ended_.AddBlobsInUse(hashes);
    return hashes;
}

std::optional<std::vector<TaskStatus>> Scheduler::Tasks(const std::string& job_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return std::nullopt;
    return it->second->Statuses(leases_, clock_());
}

std::optional<Scheduler::LeaseHolder> Scheduler::HolderOf(const std::string& lease_id,
                                                          const std::string& worker) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::optional<LeaseRef> ref = Resolve(lease_id, worker);
    if (!ref) return std::nullopt;
    return LeaseHolder{ref->job->id(),      ref->lease->task,
                       ref->lease->attempt, worker,
                       ref->lease->current, ref->job->execution->ResultParts(ref->lease->task)};
}

size_t Scheduler::workers_tracked() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return workers_.size();
}

std::vector<WorkerStatus> Scheduler::Workers() {
    std::lock_guard<std::mutex> lock(mutex_);
    const absl::Time now = clock_();
    workers_.ForgetSilent(now);
    const std::map<std::string, const Lease*> held = leases_.CurrentByWorker();
    std::vector<WorkerStatus> workers;
    std::vector<WorkerRegistry::Entry> entries = workers_.List();
    const size_t live = entries.size();
    for (WorkerRegistry::Entry& entry : workers_.Offline()) entries.push_back(std::move(entry));
    for (WorkerRegistry::Entry& entry : entries) {
        WorkerStatus& w = workers.emplace_back();
        w.offline = workers.size() > live;
        w.control = ControlOf(entry.id, entry.about);
        w.last_seen = entry.last_seen;
        w.id = std::move(entry.id);
        w.name = std::move(entry.about.name);
        w.address = std::move(entry.about.address);
        w.version = std::move(entry.about.version);
        w.since_seen = now - entry.last_seen;
        w.tags = std::move(entry.about.tags);
        if (auto it = held.find(w.id); it != held.end()) {
            w.job_id = it->second->job_id;
            w.task = it->second->task;
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
    for (const auto& [worker, lease] : leases_.CurrentByWorker()) {
        load.workers_busy += workers_.IsLive(worker, now);
    }
    return load;
}

absl::StatusOr<std::vector<Scheduler::JobRun>> Scheduler::Recover() {
    // The store is read before the lock is taken.
    struct Stored {
        JobRecord record;
        absl::StatusOr<std::map<int, JobStore::RecordedTask>> results;
    };
    std::vector<Stored> stored;
    std::map<std::string, DependencyState> ended;  // the jobs a recovered job may run after
    uint64_t last_seq = 0;
    // A store that cannot list must not start an empty server.
    absl::StatusOr<std::vector<JobRecord>> recorded = store_.List();
    if (!recorded.ok()) return recorded.status();
    for (JobRecord& record : *recorded) {
        last_seq = std::max(last_seq, record.seq);
        if (IsFinal(record.state)) {
            ended[record.id] = {record.id, record.state, record.error};
            continue;
        }
        const std::string id = record.id;
        stored.push_back({std::move(record), store_.TaskResults(id)});
    }
    Locked locked(*this);
    next_seq_ = std::max(next_seq_, last_seq + 1);
    std::vector<JobRun> rendered;
    for (Stored& s : stored) {
        if (active_.count(s.record.id)) continue;
        // One job that cannot be taken up (its task results unreadable, or a spec this build
        // refuses, such as a shot over a newer limit) fails alone; the farm starts with the rest.
        const std::string id = s.record.id;
        absl::StatusOr<bool> done = s.results.ok() ? TakeUp(s.record, *s.results)
                                                   : absl::StatusOr<bool>(s.results.status());
        if (!done.ok()) {
            FailUnrecoverable(std::move(s.record), done.status());
            continue;
        }
        if (*done) rendered.push_back({id, active_.at(id)->run});
    }
    // A dependency whose failure was recorded before the restart, its dependents' not yet.
    std::vector<std::string> ids;
    for (const auto& [id, job] : active_) ids.push_back(id);
    for (const std::string& id : ids) {
        // A job failed as the dependent of one failed here has left.
        if (auto it = active_.find(id); it != active_.end())
            FailIfDependencyEnded(*it->second, ended);
    }
    return rendered;
}

absl::StatusOr<bool> Scheduler::TakeUp(JobRecord record,
                                       const std::map<int, JobStore::RecordedTask>& results) {
    absl::StatusOr<std::unique_ptr<Job>> made =
        Job::Make(std::move(record), options_.tile_stores, options_.speculate_after);
    if (!made.ok()) return made.status();
    return TakeUp(std::move(*made), results);
}

absl::StatusOr<bool> Scheduler::TakeUp(std::unique_ptr<Job> job,
                                       const std::map<int, JobStore::RecordedTask>& results) {
    // A record stored paused before pauses were timed: its clock stays stopped from here.
    if (job->record.paused && job->record.paused_at == absl::InfinitePast()) {
        job->record.paused_at = clock_();
    }
    // In the order they merged, so an adaptive plan appends each pass before its result
    // comes up, and a shot gives each appended pass the index it had (its frames append
    // in the order their results merged, not in index order).
    std::vector<std::pair<int, const JobStore::RecordedTask*>> in_order;
    for (const auto& [t, recorded] : results) in_order.emplace_back(t, &recorded);
    std::stable_sort(in_order.begin(), in_order.end(), [](const auto& a, const auto& b) {
        return a.second->order < b.second->order;
    });
    for (const auto& [t, stored_result] : in_order) {
        const JobStore::RecordedTask& recorded = *stored_result;
        // The store wrote what merged before, so this cannot fail unless the file was
        // damaged; the task is then simply rendered again.
        if (!job->execution->MergeRecorded(t, recorded.result).ok()) {
            Log()->warn("job={} task={}: the recorded result is unusable, rendering it again",
                        job->id(), t);
            continue;
        }
        job->Move(t, TaskState::kDone);
        job->Queue({});
        job->Restore(t, recorded.history);
    }
    job->Queue(job->execution->Start());
    job->Sync();
    Log()->info("job={} recovered: {}/{} tasks done, {} leases handed out before", job->id(),
                job->record.tasks_done, job->record.tasks_total, job->record.tasks_leased);
    const bool rendered = EnforceTimeLimit(*job, clock_()) || job->execution->Complete();
    Save(*job);
    job->run = next_run_++;
    active_[job->id()] = std::move(job);
    return rendered;
}

absl::StatusOr<Scheduler::Requeued> Scheduler::RequeueJob(const std::string& job_id) {
    {
        Locked locked(*this);
        if (auto it = active_.find(job_id); it != active_.end()) {
            Job& job = *it->second;
            int reset = 0;
            for (ScheduledJob::Task& task : job.tasks) {
                reset += task.failures > 0;
                task.failures = 0;
                task.failed_on.clear();
            }
            job.record.worker_failures.clear();
            job.record.last_error.clear();
            Log()->info("job={} requeued: {} failed tasks reset, blocklist cleared", job_id, reset);
            const uint64_t ticket = Save(job);
            Requeued requeued{job.record, job.run};
            locked.lock.unlock();
            if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) return s;
            return requeued;
        }
        if (ended_.Find(job_id)) return JustEnded(job_id);
    }
    return Reopen(job_id, nullptr, std::nullopt);
}

absl::StatusOr<Scheduler::Requeued> Scheduler::RequeueFrames(const std::string& job_id,
                                                             const FrameRange& frames,
                                                             const RemoveFrameFiles& remove_files) {
    {
        Locked locked(*this);
        if (active_.count(job_id)) {
            return absl::FailedPreconditionError(absl::StrCat(
                "job ", job_id,
                " is queued or running: --frames renders frames of an ended job again (cancel "
                "it first, or wait for it to end)"));
        }
        if (ended_.Find(job_id)) return JustEnded(job_id);
    }
    return Reopen(job_id, remove_files, frames);
}

absl::StatusOr<Scheduler::Requeued> Scheduler::Reopen(const std::string& job_id,
                                                      const RemoveFrameFiles& remove_files,
                                                      const std::optional<FrameRange>& frames) {
    // The store is read without the lock.
    absl::StatusOr<JobRecord> stored = store_.Get(job_id);
    if (!stored.ok()) return stored.status();
    if (frames) {
        if (absl::Status s = CheckRequeuedFrames(*stored, *frames); !s.ok()) return s;
    }
    if (absl::Status s = ReopenJob(*stored, frames.has_value()); !s.ok()) return s;
    absl::StatusOr<std::map<int, JobStore::RecordedTask>> results = store_.TaskResults(job_id);
    if (!results.ok()) return results.status();
    stored->worker_failures.clear();
    stored->last_error.clear();
    Locked locked(*this);
    absl::StatusOr<std::map<std::string, DependencyState>> after =
        DependencyStates(stored->spec.after, locked);
    if (!after.ok()) return after.status();
    if (active_.count(job_id) || ended_.Find(job_id)) {
        return absl::AbortedError(
            absl::StrCat("job ", job_id, " was requeued by another call meanwhile"));
    }
    // Refused, not failed again: a requeue that could only fail changes nothing (a shot's
    // frames dropped for it would be lost).
    if (std::optional<std::string> why = EndedDependencyFailure(*stored, *after)) {
        return absl::FailedPreconditionError(
            absl::StrCat("job ", job_id, " cannot run: ", *why, "; requeue that one first"));
    }
    // Jobs its success released would wait for it again mid-render, and a cycle could close
    // through them (their dependencies were checked against it as ended).
    std::vector<std::string> dependents;
    for (const auto& [id, other] : active_) {
        const std::vector<std::string>& of = other->record.spec.after;
        if (std::find(of.begin(), of.end(), job_id) != of.end()) dependents.push_back(id);
    }
    if (!dependents.empty()) {
        return absl::FailedPreconditionError(
            absl::StrCat("job ", job_id, " has jobs running after it (",
                         absl::StrJoin(dependents, ", "), "): requeue it once they have ended"));
    }
    if (absl::Status s = CheckActiveJobLimit("requeue"); !s.ok()) return s;
    absl::StatusOr<std::unique_ptr<Job>> made =
        Job::Make(std::move(*stored), options_.tile_stores, options_.speculate_after);
    if (!made.ok()) return made.status();
    Requeued requeued;
    std::vector<int> dropped;  // tasks of the frames rendered again, their results removed
    if (frames) {
        std::set<int> again;
        for (const auto& [t, result] : *results) {
            // An index the plan lacks (a damaged store): TakeUp renders it again.
            if (t < 0 || size_t(t) >= (*made)->execution->task_count()) continue;
            TaskStatus task;
            (*made)->execution->Describe(t, task);
            if (std::none_of(task.frames.begin(), task.frames.end(),
                             [&](int f) { return frames->Contains(f); })) {
                continue;
            }
            dropped.push_back(t);
            again.insert(task.frames.begin(), task.frames.end());  // a chunk's other frames too
        }
        for (int t : dropped) results->erase(t);
        for (FrameProgress& frame : (*made)->record.frames) {
            if (frames->Contains(frame.frame) || again.count(frame.frame)) {
                frame.result_path.clear();
                requeued.frames.push_back(frame.frame);
            }
        }
    }
    absl::StatusOr<bool> rendered = TakeUp(std::move(*made), *results);
    if (!rendered.ok()) return rendered.status();
    Job& job = *active_.at(job_id);
    Log()->info("job={} requeued: {}/{} tasks done kept, the rest queued{}", job_id,
                job.record.tasks_done, job.record.tasks_total,
                frames ? absl::StrCat(" (frames ", FrameRangeText(*frames), " again)") : "");
    const uint64_t ticket = Save(job, dropped);
    requeued.record = job.record;
    requeued.run = job.run;
    requeued.rendered = *rendered;
    // Leases and merges wait for the lock: no frame of this run is written yet.
    if (remove_files && !requeued.frames.empty()) remove_files(requeued.frames);
    locked.lock.unlock();
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) return s;
    return requeued;
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
    if (workers_.IsQuarantined(worker, now) || workers_.IsQuarantined(TokenStrikes(worker), now))
        return std::nullopt;
    // Seen just now: the registry keeps it.
    const WorkerDescription& self = *workers_.AboutOf(worker);
    if (ControlOf(worker, self) != WorkerControl::kEnabled) return std::nullopt;
    if (const std::string principal = PrincipalOf(worker);
        !principal.empty() && leases_.CurrentOf(principal) >= options_.max_leases_per_token) {
        return std::nullopt;
    }
    const std::vector<std::string>& tags = self.tags;
    Job* best = nullptr;
    int best_task = -1;
    std::vector<std::string> stranded;  // jobs with queued tasks this blocklisted worker asks for
    for (auto& [id, job] : active_) {
        if (job->record.paused || WaitsForDependency(*job)) continue;
        if (IsBlocklisted(job->record, worker)) {
            if (!job->states.queued().empty()) stranded.push_back(id);
            continue;
        }
        if (best && (job->record.spec.priority < best->record.spec.priority ||
                     (job->record.spec.priority == best->record.spec.priority &&
                      job->record.seq > best->record.seq))) {
            continue;
        }
        if (!Admits(*job, worker, tags)) continue;
        for (int t : job->states.queued()) {
            if (!MayTake(*job, t, worker, now)) continue;
            best = job.get();
            best_task = t;
            break;
        }
    }
    for (const std::string& id : stranded) {
        // Failing one may fail the others as its dependents.
        if (auto it = active_.find(id); it != active_.end()) FailIfStranded(*it->second);
    }
    if (best) return Grant(*best, best_task, worker, now);
    for (auto& [id, job] : active_) {
        if (!Admits(*job, worker, tags)) continue;
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
    if (!job.states.queued().empty() || job.record.paused || IsBlocklisted(job.record, worker)) {
        return -1;
    }
    int oldest = -1;
    for (int t = 0; t < int(job.tasks.size()); ++t) {
        const ScheduledJob::Task& task = job.tasks[size_t(t)];
        if (job.states.state(t) != TaskState::kLeased || task.failed_on.count(worker) ||
            !job.speculation.IsStraggler(now - task.leased_at)) {
            continue;
        }
        const std::vector<const Lease*> current = leases_.Current(job.id(), t);
        if (current.size() != 1 || current[0]->worker == worker) continue;
        if (oldest < 0 || task.leased_at < job.tasks[size_t(oldest)].leased_at) oldest = t;
    }
    return oldest;
}

TaskAssignment Scheduler::Grant(Job& job, int t, const std::string& worker, absl::Time now) {
    ScheduledJob::Task& task = job.tasks[size_t(t)];
    if (job.states.state(t) == TaskState::kQueued) {
        job.Move(t, TaskState::kLeased);
        task.leased_at = now;
    }
    ++task.attempts;
    ++job.record.tasks_leased;
    metrics_.leases.Add();
    TaskAssignment lease;
    lease.lease_id = leases_.Grant(job.id(), t, task.attempts, worker, now + options_.lease);
    // A lease is not durable (a restart queues its task again): the record is written when the
    // job starts (its time limit counts from then), else with its next recorded change.
    if (job.record.state == JobState::kQueued) {
        job.MoveTo(clock_(), JobState::kRunning);
        Save(job);
    } else {
        Announce(job);
    }
    Log()->debug("job={} task={} leased to {} (attempt {})", job.id(), t, LogSafe(worker),
                 task.attempts);
    lease.job_id = job.id();
    lease.spec = job.record.spec;
    lease.lease = options_.lease;
    lease.heartbeat_interval = options_.heartbeat_interval;
    job.execution->Lease(t, worker, lease);
    return lease;
}

bool Scheduler::EnforceTimeLimit(Job& job, absl::Time now) {
    if (job.record.paused) return false;  // its clock is stopped
    const std::optional<std::vector<int>> dropped =
        job.execution->EnforceTimeLimit(job.record.started + job.record.paused_for, now);
    if (!dropped) return false;
    for (int t : *dropped) {
        leases_.EndTask(job.id(), t);
        job.Move(t, TaskState::kDropped);
    }
    Log()->info("job={} time limit of {} s reached: {} tasks dropped, {} tasks merged", job.id(),
                job.record.spec.adaptive.time_limit, dropped->size(), job.execution->tasks_done());
    Save(job);
    // When nothing was dropped, the last result completed the job and Complete said so.
    return !dropped->empty() && job.execution->Complete();
}

std::vector<Scheduler::JobRun> Scheduler::EnforceTimeLimits() {
    Locked locked(*this);
    std::vector<JobRun> rendered;
    const absl::Time now = clock_();
    for (auto& [id, job] : active_) {
        if (EnforceTimeLimit(*job, now)) rendered.push_back({id, job->run});
    }
    return rendered;
}

bool Scheduler::MayWorkOn(const Job& job, const std::string& id,
                          const WorkerDescription& about) const {
    return ControlOf(id, about) == WorkerControl::kEnabled && !IsBlocklisted(job.record, id) &&
           HasAllTags(about.tags, job.record.spec.tags);
}

bool Scheduler::PreferredMayTake(const Job& job, int t, absl::Time now) const {
    const std::string preferred = job.execution->PreferredWorker(t);
    if (preferred.empty() || job.tasks[size_t(t)].failed_on.count(preferred) ||
        !workers_.IsLive(preferred, now) || workers_.IsQuarantined(preferred, now) ||
        workers_.IsQuarantined(TokenStrikes(preferred), now)) {
        return false;
    }
    const WorkerDescription* about = workers_.AboutOf(preferred);
    return about && MayWorkOn(job, preferred, *about);
}

bool Scheduler::MayTake(const Job& job, int t, const std::string& worker, absl::Time now) const {
    const ScheduledJob::Task& task = job.tasks[size_t(t)];
    // A task keeps to its preferred worker (the one holding its chunk) while that one lives and
    // may take it, unless it failed there: else it would wait for as long as that worker lives
    // (a worker blocklisted from the job, disabled, without its tags or quarantined does not
    // take it).
    if (job.execution->PreferredWorker(t) != worker && PreferredMayTake(job, t, now)) return false;
    if (!task.failed_on.count(worker)) return true;
    // It failed here: it waits for a live worker it has not failed on that may take the job
    // (enabled, not blocklisted from it, with its tags: a worker that may not would hold it
    // forever). Once it has failed on every such worker it is tried again anywhere, so its
    // failures end the job. The workers kept are the live ones.
    size_t eligible = 0, eligible_failed = 0;
    for (const WorkerRegistry::Entry& entry : workers_.List()) {
        if (!MayWorkOn(job, entry.id, entry.about)) continue;
        ++eligible;
        eligible_failed += task.failed_on.count(entry.id);
    }
    return eligible <= eligible_failed;
}

WorkerControl Scheduler::ControlOf(const std::string& id, const WorkerDescription& about) const {
    auto it = controls_.find(about.name.empty() ? id : about.name);
    return it == controls_.end() ? WorkerControl::kEnabled : it->second;
}

std::optional<std::string> Scheduler::WorkerKey(const std::string& name_or_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<WorkerRegistry::Entry> entries = workers_.List();
    for (WorkerRegistry::Entry& entry : workers_.Offline()) entries.push_back(std::move(entry));
    for (const WorkerRegistry::Entry& entry : entries) {
        if (entry.id == name_or_id) return entry.about.name.empty() ? entry.id : entry.about.name;
    }
    for (const WorkerRegistry::Entry& entry : entries) {
        if (entry.about.name == name_or_id) return name_or_id;
    }
    if (controls_.count(name_or_id)) return name_or_id;
    return std::nullopt;
}

void Scheduler::SetWorkerControl(const std::string& key, WorkerControl control) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (control == WorkerControl::kEnabled) {
        controls_.erase(key);
    } else {
        controls_[key] = control;
    }
    // A re-enabled worker waiting in LeaseTask looks for work again.
    ++version_;
    changed_.notify_all();
}

bool Scheduler::Admits(const Job& job, const std::string& worker,
                       const std::vector<std::string>& tags) const {
    const JobSpec& spec = job.record.spec;
    if (!HasAllTags(tags, spec.tags)) return false;
    if (spec.max_workers <= 0) return true;
    const std::set<std::string> holders = leases_.WorkersOf(job.id());
    return holders.count(worker) || int(holders.size()) < spec.max_workers;
}

JobRecord Scheduler::ReadRecord(const Job& job, absl::Time now) const {
    JobRecord record = job.record;
    record.waiting_for.clear();  // a reader's view, never the job's own
    std::vector<DependencyState> waiting;
    for (const std::string& dep : record.spec.after) {
        if (auto it = active_.find(dep); it != active_.end()) {
            waiting.push_back({dep, it->second->record.state});
            record.waiting_for.push_back(dep);
        }
    }
    if (!waiting.empty()) {
        record.waiting_reason = WaitingForDependencies(waiting);
    } else if (!record.spec.tags.empty() && !job.states.queued().empty() &&
               !workers_.AnyLiveHas(record.spec.tags, now)) {
        record.waiting_reason = WaitingForTags(record.spec.tags);
    }
    return record;
}

std::optional<Scheduler::LeaseRef> Scheduler::Resolve(const std::string& lease_id,
                                                      const std::string& worker) {
    const Lease* lease = leases_.Find(lease_id);
    if (!lease || lease->worker != worker) return std::nullopt;
    auto it = active_.find(lease->job_id);
    if (it == active_.end()) return std::nullopt;
    return LeaseRef{it->second.get(), lease, lease_id};
}

bool Scheduler::Heartbeat(const std::string& lease_id, const std::string& worker) {
    Locked locked(*this);
    const absl::Time now = clock_();
    if (!Resolve(lease_id, worker)) return false;  // a made-up id is not kept
    workers_.Seen(worker, now);
    // Only a lease still held clears strikes: a heartbeat on an expired one would otherwise
    // lift its token's quarantine.
    if (!leases_.Extend(lease_id, now + options_.lease)) return false;
    workers_.Worked(worker);
    workers_.Worked(TokenStrikes(worker));
    return true;
}

absl::StatusOr<Scheduler::Completion> Scheduler::Complete(const std::string& lease_id,
                                                          const std::string& worker,
                                                          const TaskResult& result) {
    Locked locked(*this);
    const absl::Time now = clock_();
    const absl::StatusOr<LeaseRef> ref = ResultLease(lease_id, worker, now);
    if (!ref.ok()) return ref.status();
    Job& job = *ref->job;
    const int t = ref->lease->task;
    Completion completion{job.id(), job.run};
    const TaskState state = job.states.state(t);
    if (state == TaskState::kDone || state == TaskState::kDropped) return completion;
    TaskResult made = result;
    // Done by another worker than the one the task waited for, which is gone or may not take it
    // now: the execution prefers this one from now on (it holds what the task built).
    const std::string preferred = job.execution->PreferredWorker(t);
    if (!preferred.empty() && preferred != worker && !PreferredMayTake(job, t, now)) {
        made.takes_over = worker;
    }
    absl::StatusOr<JobExecution::Merged> merged = job.execution->Merge(t, made);
    if (!merged.ok()) return Refuse(*ref, worker, merged.status());
    workers_.Worked(worker);
    workers_.Worked(TokenStrikes(worker));
    MarkDone(job, t, now);
    job.AddTimes(t, result);
    job.Queue(merged->appended);
    if (!merged->job_error.ok()) {
        FailJob(job, std::string(merged->job_error.message()));
        return completion;
    }
    if (merged->sweep) {
        Log()->info("job={} radiosity sweep {}: relative residual {:.3g}{}", job.id(),
                    merged->sweep->iterations, merged->sweep->residual,
                    merged->sweep->converged ? ", solved" : "");
        completion.sweep = std::move(merged->sweep);
    }
    completion.frames_completed = std::move(merged->frames_completed);
    EnforceTimeLimit(job, now);
    const std::optional<std::string> record = job.execution->RecordOf(result);
    if (!record) {  // soft state, not recorded
        Announce(job);
        return completion;
    }
    job.Sync();
    // The record holds what the execution needs to merge the result again after a restart.
    const uint64_t ticket = store_.QueueTaskDone(job.record, t, *record, job.History(t, leases_));
    ++version_;
    changed_.notify_all();
    Log()->debug("job={} task={} done by {} ({}/{})", job.id(), t, LogSafe(worker),
                 job.record.tasks_done, job.record.tasks_total);
    completion.job_rendered = job.execution->Complete();
    completion.unrecorded = Completion::Unrecorded{t, ticket};
    locked.lock.unlock();
    if (completion.job_rendered) return completion;  // recorded while the image is written
    if (absl::Status s = AwaitRecorded(completion); !s.ok()) return s;
    completion.unrecorded.reset();
    return completion;
}

absl::Status Scheduler::AwaitRecorded(const Completion& completion) {
    if (!completion.unrecorded) return absl::OkStatus();
    // The worker hears "done" only once the result is durable.
    const absl::Status s = store_.WaitDurable(completion.unrecorded->ticket);
    if (s.ok()) return s;
    // The merge cannot be taken back, and a job whose results are not all recorded would not
    // survive a restart: the run that merged it fails here, and the worker hears why. A run
    // requeued since that one ended (cancelled during this wait) read the recorded results, and
    // renders the task again.
    {
        Locked locked(*this);
        if (auto it = active_.find(completion.job_id);
            it != active_.end() && it->second->run == completion.run) {
            FailJob(*it->second, absl::StrCat("recording the result of task ",
                                              completion.unrecorded->task, ": ", s.message()));
        }
    }
    return absl::Status(s.code(), absl::StrCat("job=", completion.job_id, ": ", s.message()));
}

absl::StatusOr<Scheduler::LeaseRef> Scheduler::ResultLease(const std::string& lease_id,
                                                           const std::string& worker,
                                                           absl::Time now) {
    const std::optional<LeaseRef> ref = Resolve(lease_id, worker);
    if (!ref) {
        Log()->warn("result for lease {} from {} refused: not a lease it holds", LogSafe(lease_id),
                    LogSafe(worker));
        return absl::FailedPreconditionError(absl::StrCat(
            "lease ", lease_id, " is not one of worker ", worker, " in a running job"));
    }
    workers_.Seen(worker, now);
    return *ref;
}

absl::Status Scheduler::Refuse(const LeaseRef& ref, const std::string& worker,
                               const absl::Status& why) {
    const std::string error = absl::StrCat("job=", ref.job->id(), " task=", ref.lease->task,
                                           " from ", worker, ": ", why.message());
    if (ref.lease->current) RequeueReported(ref, absl::StrCat("result refused: ", why.message()));
    return absl::InvalidArgumentError(error);
}

void Scheduler::MarkDone(Job& job, int t, absl::Time now) {
    ScheduledJob::Task& task = job.tasks[size_t(t)];
    task.finished = now;
    if (job.states.state(t) == TaskState::kLeased) {
        // Whoever else holds a lease of it (a retry or a speculative copy) learns at its next
        // heartbeat.
        leases_.EndTask(job.id(), t);
        job.speculation.TaskDone(now - task.leased_at);
        metrics_.task_seconds.Observe(absl::ToDoubleSeconds(now - task.leased_at));
    }
    job.Move(t, TaskState::kDone);
    metrics_.tasks_done.Add(now, 1);
    metrics_.samples_done.Add(now, job.execution->TaskSamples(t));
}

void Scheduler::Publish(const std::string& job_id, bool converged,
                        const absl::StatusOr<std::string>& hash,
                        std::shared_ptr<const std::string> bytes) {
    Locked locked(*this);
    auto it = active_.find(job_id);
    if (it == active_.end()) return;  // cancelled meanwhile
    Job& job = *it->second;
    if (!hash.ok()) {
        FailJob(job, absl::StrCat("storing the radiosity: ", hash.status().message()));
        return;
    }
    absl::StatusOr<std::vector<int>> ready =
        job.execution->Publish(converged, *hash, std::move(bytes));
    if (!ready.ok()) {
        FailJob(job, std::string(ready.status().message()));
        return;
    }
    job.Queue(*ready);
    if (converged) {
        Save(job);  // the display tiles, whose results are recorded, start
    } else {
        Announce(job);
    }
}

absl::Status Scheduler::Fail(const std::string& lease_id, const std::string& worker,
                             const std::string& reason, FailureKind kind) {
    Locked locked(*this);
    const std::optional<LeaseRef> ref = Resolve(lease_id, worker);
    if (!ref || !ref->lease->current) return absl::OkStatus();
    const std::string why = absl::StrCat(reason, " (worker ", worker, ")");
    if (kind == FailureKind::kTaskError) {
        RequeueReported(*ref, why);
    } else {
        Requeue(*ref, why, false);
    }
    return absl::OkStatus();
}

void Scheduler::RequeueReported(const LeaseRef& ref, const std::string& reason) {
    const std::string job_id = ref.job->id(), worker = ref.lease->worker;
    const bool blocked = CountWorkerFailure(ref.job->record, worker, reason);
    Requeue(ref, reason, true);  // may end the job
    auto it = active_.find(job_id);
    if (!blocked || it == active_.end()) return;
    Log()->warn("job={} worker {} blocklisted: it failed {} of the job's tasks", job_id,
                LogSafe(worker), it->second->record.spec.blocklist_after);
    FailIfStranded(*it->second);
}

void Scheduler::FailIfStranded(Job& job) {
    workers_.ForgetSilent(clock_());
    std::vector<std::string> live;
    for (const WorkerRegistry::Entry& entry : workers_.List()) live.push_back(entry.id);
    if (std::optional<std::string> error = StrandedError(job.record, live)) FailJob(job, *error);
}

void Scheduler::Requeue(const LeaseRef& ref, const std::string& reason, bool counted) {
    Job& job = *ref.job;
    const int t = ref.lease->task;
    const int attempt = ref.lease->attempt;
    ScheduledJob::Task& task = job.tasks[size_t(t)];
    leases_.End(ref.id);
    if (counted) {
        metrics_.task_failures.Add();
        ++task.failures;
        task.failed_on.insert(ref.lease->worker);
        task.last_error = reason;
        job.record.last_error = absl::StrCat("task ", t, ": ", reason);
    }
    Log()->warn("job={} task={} attempt {} failed: {}{}", job.id(), t, attempt, LogSafe(reason),
                counted ? "" : " (not counted)");
    if (task.failures >= job.record.spec.max_attempts) {
        FailJob(job, absl::StrCat("task ", t, " failed ", Plural(task.failures, "time"),
                                  "; last: ", reason));
        return;
    }
    // Otherwise another lease of it still renders; or, when several of its leases expired in
    // one tick (TakeExpired ends them all first), an earlier one's requeue queued it already.
    if (leases_.Current(job.id(), t).empty() && job.states.state(t) == TaskState::kLeased) {
        job.Move(t, TaskState::kQueued);
        ++job.record.retries;
    }
    Save(job);
}

void Scheduler::FailUnrecoverable(JobRecord record, const absl::Status& why) {
    const absl::Status moved = TransitionJob(record, JobState::kFailed, clock_());
    if (!moved.ok()) Log()->error("job={}: {}", record.id, std::string(moved.message()));
    record.error =
        absl::StrCat("cannot be taken up after the coordinator restarted: ", why.message());
    Log()->error("job={} failed: {}", record.id, LogSafe(record.error));
    const uint64_t ticket = store_.QueuePut(record);
    ended_.Add(std::move(record), ticket);
}

void Scheduler::FailJob(Job& job, const std::string& error) {
    job.MoveTo(clock_(), JobState::kFailed);
    job.record.error = error;
    Log()->error("job={} failed: {}", job.record.id, LogSafe(error));
    EndJob(job);
}

JobRecord Scheduler::EndJob(Job& job) {
    const std::string id = job.record.id;
    job.record.paused = false;  // an ended job is cancelled, failed or succeeded, not paused
    job.record.paused_at = absl::InfinitePast();
    std::vector<TaskStatus> statuses = job.Statuses(leases_, clock_());
    leases_.ForgetJob(id);
    const uint64_t ticket = Save(job);
    JobRecord record = job.record;
    ended_tasks_.emplace_back(record, std::move(statuses));
    active_.erase(id);  // destroys `job`
    const std::optional<std::string> why =
        DependencyFailure({record.id, record.state, record.error});
    JobRecord added = ended_.Add(std::move(record), ticket);
    if (!why) return added;
    // Its dependents fail, and theirs in turn: each FailJob ends here again and adds its own to
    // the list the outermost call works through (a chain of thousands recursing would not).
    for (const auto& [other, dependent] : active_) {
        const std::vector<std::string>& after = dependent->record.spec.after;
        if (std::find(after.begin(), after.end(), id) != after.end()) {
            failing_dependents_.emplace_back(other, *why);
        }
    }
    if (failing_dependents_busy_) return added;
    failing_dependents_busy_ = true;
    while (!failing_dependents_.empty()) {
        auto [other, reason] = std::move(failing_dependents_.front());
        failing_dependents_.pop_front();
        if (auto it = active_.find(other); it != active_.end()) FailJob(*it->second, reason);
    }
    failing_dependents_busy_ = false;
    return added;
}

bool Scheduler::WaitsForDependency(const Job& job) const {
    for (const std::string& dep : job.record.spec.after) {
        if (active_.count(dep)) return true;
    }
    return false;
}

absl::StatusOr<std::map<std::string, DependencyState>> Scheduler::DependencyStates(
    const std::vector<std::string>& ids, Locked& locked) {
    std::map<std::string, DependencyState> states;
    if (ids.empty()) return states;
    while (true) {
        // A job queued or running when the store was read and not in memory after it ended and
        // left memory meanwhile: the store is read again.
        const uint64_t left_before = left_memory_;
        locked.lock.unlock();
        std::map<std::string, absl::StatusOr<JobRecord>> stored;
        for (const std::string& id : ids) stored.emplace(id, store_.Get(id));
        locked.lock.lock();
        bool stale = false;
        for (const auto& [id, record] : stored) {
            DependencyState& state = states[id];
            state = {id};
            if (auto it = active_.find(id); it != active_.end()) {
                state.state = it->second->record.state;
            } else if (const JobRecord* ended = ended_.Find(id)) {
                state = {id, ended->state, ended->error};
            } else if (record.ok()) {
                state = {id, record->state, record->error};
                stale |= !IsFinal(record->state);
            } else if (!absl::IsNotFound(record.status())) {
                return record.status();
            }
        }
        if (!stale || left_memory_ == left_before) return states;
    }
}

std::optional<std::string> Scheduler::EndedDependencyFailure(
    const JobRecord& job, const std::map<std::string, DependencyState>& known) const {
    for (const std::string& dep : job.spec.after) {
        if (active_.count(dep)) continue;
        DependencyState state{dep};
        if (const JobRecord* ended = ended_.Find(dep)) {
            state = {dep, ended->state, ended->error};
        } else if (auto it = known.find(dep); it != known.end()) {
            state = it->second;
        }
        if (std::optional<std::string> why = DependencyFailure(state)) return why;
    }
    return std::nullopt;
}

bool Scheduler::FailIfDependencyEnded(Job& job,
                                      const std::map<std::string, DependencyState>& known) {
    std::optional<std::string> why = EndedDependencyFailure(job.record, known);
    if (why) FailJob(job, *why);
    return why.has_value();
}

absl::StatusOr<JobRecord> Scheduler::AddDependencies(const std::string& job_id,
                                                     const std::vector<std::string>& after) {
    JobRecord record;
    uint64_t ticket = 0;
    {
        Locked locked(*this);
        absl::StatusOr<std::map<std::string, DependencyState>> states =
            DependencyStates(after, locked);
        if (!states.ok()) return states.status();
        absl::StatusOr<Job*> active = ActiveJob(job_id, locked);
        if (!active.ok()) return active.status();
        Job& job = **active;
        if (job.record.state != JobState::kQueued) {
            return absl::FailedPreconditionError(
                absl::StrCat("job ", job_id, " is ", JobStateName(job.record.state),
                             ": dependencies are added only to a queued job"));
        }
        absl::StatusOr<std::vector<std::string>> added =
            CheckDependencyIds(after, "after", job.record.spec.after);
        if (!added.ok()) return added.status();
        for (const std::string& dep : *added) {
            if (absl::Status s = CheckNewDependency(states->at(dep)); !s.ok()) return s;
        }
        // Only jobs still held can close a cycle: an ended one waits for nothing.
        const std::optional<std::vector<std::string>> cycle =
            FindCycle(job_id, *added, [&](const std::string& id) {
                auto it = active_.find(id);
                return it == active_.end() ? std::vector<std::string>{}
                                           : it->second->record.spec.after;
            });
        if (cycle) return absl::FailedPreconditionError(CycleText(*cycle));
        std::vector<std::string>& deps = job.record.spec.after;
        deps.insert(deps.end(), added->begin(), added->end());
        Log()->info("job={} runs after {} more: {}", job_id, added->size(),
                    absl::StrJoin(*added, ","));
        ticket = Save(job);
        record = ReadRecord(job, clock_());
    }
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) return s;
    return record;
}

absl::StatusOr<JobRecord> Scheduler::Cancel(const std::string& job_id) {
    std::optional<JobRecord> cancelled;
    {
        Locked locked(*this);
        if (auto it = active_.find(job_id); it != active_.end()) {
            it->second->MoveTo(clock_(), JobState::kCancelled);
            Log()->info("job={} cancelled", job_id);  // before its dependents fail
            cancelled = EndJob(*it->second);
        } else if (const JobRecord* ended = ended_.Find(job_id)) {
            return AlreadyEnded(*ended);
        }
    }  // the cancellation is durable here, or logged as not recorded
    if (cancelled) return *cancelled;
    absl::StatusOr<JobRecord> record = store_.Get(job_id);
    if (!record.ok()) return record.status();
    return AlreadyEnded(*record);
}

absl::StatusOr<Scheduler::Job*> Scheduler::ActiveJob(const std::string& job_id, Locked& locked) {
    auto it = active_.find(job_id);
    if (it != active_.end()) return it->second.get();
    if (const JobRecord* ended = ended_.Find(job_id)) return AlreadyEnded(*ended);
    locked.lock.unlock();  // the store is never read under the lock
    absl::StatusOr<JobRecord> stored = store_.Get(job_id);
    if (!stored.ok()) return stored.status();
    return AlreadyEnded(*stored);
}

absl::StatusOr<JobRecord> Scheduler::SetPaused(const std::string& job_id, bool paused) {
    JobRecord record;
    uint64_t ticket = 0;
    {
        Locked locked(*this);
        absl::StatusOr<Job*> job = ActiveJob(job_id, locked);
        if (!job.ok()) return job.status();
        Log()->info("job={} {}", job_id, paused ? "paused" : "resumed");
        const absl::Time now = clock_();
        JobRecord& r = (*job)->record;
        if (paused && !r.paused) r.paused_at = now;
        if (!paused && r.paused) {
            r.paused_for += std::max(absl::ZeroDuration(), now - r.paused_at);
            r.paused_at = absl::InfinitePast();
        }
        r.paused = paused;
        ticket = Save(**job);
        record = (*job)->record;
    }
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) return s;
    return record;
}

absl::StatusOr<JobRecord> Scheduler::SetPriority(const std::string& job_id, int priority) {
    JobRecord record;
    uint64_t ticket = 0;
    {
        Locked locked(*this);
        absl::StatusOr<Job*> active = ActiveJob(job_id, locked);
        if (!active.ok()) return active.status();
        Job& job = **active;
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
    const std::vector<std::string> expired = leases_.TakeExpired(now);
    for (const std::string& lease_id : expired) {
        const Lease* lease = leases_.Find(lease_id);  // unknown once an earlier one failed its job
        const std::optional<LeaseRef> ref = lease ? Resolve(lease_id, lease->worker) : std::nullopt;
        if (!ref) continue;
        if (lease->heard) {
            Requeue(*ref,
                    absl::StrCat("lease expired: worker ", lease->worker, " sent no heartbeat for ",
                                 absl::FormatDuration(options_.lease)),
                    true);
            continue;
        }
        // Workers heartbeat as soon as they take a task: one that never did abandoned it, or
        // never got it. Counting that against the task would let one token that leases and
        // never answers fail every queued job; it counts against the worker instead.
        const std::string worker = lease->worker;
        Requeue(*ref, absl::StrCat("lease abandoned: worker ", worker, " never heartbeated"),
                false);
        // Strikes against the worker, and against its token as a whole: one that leases under
        // a fresh id each time would never be quarantined as a worker.
        for (const std::string& who : {worker, TokenStrikes(worker)}) {
            if (!who.empty() &&
                workers_.Abandoned(who, now, options_.lease * options_.quarantine_leases)) {
                Log()->warn("{} quarantined for {}: {} leases in a row expired unheard",
                            who == worker ? "worker " + LogSafe(worker) : LogSafe(who),
                            absl::FormatDuration(options_.lease * options_.quarantine_leases),
                            WorkerRegistry::kAbandonedInARow);
            }
        }
    }
    return int(expired.size());
}

namespace {

// The image of a snapshot taken under the lock, read outside it, and its estimated error.
absl::StatusOr<Scheduler::JobImage> ReadSnapshot(Scheduler::JobImage snapshot,
                                                 const JobExecution::ImageReader& read) {
    absl::StatusOr<Image> image = read();
    if (!image.ok()) return image.status();
    snapshot.image = std::move(*image);
    if (snapshot.adaptive) {
        absl::StatusOr<double> estimated = EstimatedRelativeError(snapshot.image);
        if (!estimated.ok()) return estimated.status();
        snapshot.adaptive->estimated_error = *estimated;
    }
    return snapshot;
}

}  // namespace

absl::StatusOr<Scheduler::JobImage> Scheduler::Snapshot(const std::string& job_id) const {
    JobImage snapshot;
    JobExecution::ImageReader read;  // shares the stores: outlives the job if it ends meanwhile
    {
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = active_.find(job_id);
        if (it == active_.end()) {
            return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
        }
        const Job& job = *it->second;
        snapshot.record = job.record;
        snapshot.run = job.run;
        read = job.execution->SnapshotReader();
        snapshot.adaptive = job.execution->TileReport();
    }
    return ReadSnapshot(std::move(snapshot), read);
}

absl::StatusOr<Scheduler::JobImage> Scheduler::FrameSnapshot(const std::string& job_id,
                                                             int frame) const {
    JobImage snapshot;
    JobExecution::ImageReader read;  // shares the frame's stores, as Snapshot's
    {
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = active_.find(job_id);
        if (it == active_.end()) {
            return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
        }
        const Job& job = *it->second;
        const JobExecution* execution = job.execution->FrameExecution(frame);
        if (!execution) {
            return absl::NotFoundError(absl::StrCat("job ", job_id, " renders no frame ", frame));
        }
        snapshot.record = job.record;
        snapshot.run = job.run;
        snapshot.record.spec = FrameSpec(job.record.spec, frame);
        snapshot.record.stats = execution->stats();
        read = execution->SnapshotReader();
        snapshot.adaptive = execution->TileReport();
    }
    return ReadSnapshot(std::move(snapshot), read);
}

bool Scheduler::FrameWritten(const JobRun& run, int frame,
                             const absl::StatusOr<std::string>& path) {
    Locked locked(*this);
    const std::string& job_id = run.job_id;
    auto it = active_.find(job_id);
    // Cancelled meanwhile: it keeps the frames recorded before.
    if (it == active_.end() || it->second->run != run.run) return false;
    Job& job = *it->second;
    if (!path.ok()) {
        FailJob(job, absl::StrCat("writing frame ", frame, ": ", path.status().message()));
        return true;
    }
    job.Sync();
    for (FrameProgress& f : job.record.frames) {
        if (f.frame == frame) f.result_path = *path;
    }
    Log()->info("job={} frame {} written ({}/{} frames) -> {}", job_id, frame,
                job.record.frames_done(), job.record.frames.size(), *path);
    const uint64_t ticket = Save(job);
    locked.lock.unlock();
    if (absl::Status s = store_.WaitDurable(ticket); !s.ok()) {
        Log()->error("job={} frame {}: its path is not recorded: {}", job_id, frame,
                     std::string(s.message()));
    }
    return true;
}

std::optional<uint64_t> Scheduler::RunOf(const std::string& job_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return std::nullopt;
    return it->second->run;
}

std::vector<std::pair<Scheduler::JobRun, int>> Scheduler::UnwrittenFrames() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::pair<JobRun, int>> frames;
    for (const auto& [id, job] : active_) {
        const std::vector<FrameProgress>& recorded = job->record.frames;  // in frame order
        const std::vector<FrameProgress> now = job->execution->Frames();
        for (size_t i = 0; i < now.size(); ++i) {
            const bool written = i < recorded.size() && !recorded[i].result_path.empty();
            if (now[i].done && !written) frames.emplace_back(JobRun{id, job->run}, now[i].frame);
        }
    }
    return frames;
}

void Scheduler::Finish(const JobRun& rendered, const absl::StatusOr<std::string>& result_path) {
    Locked locked(*this);
    const std::string& job_id = rendered.job_id;
    auto it = active_.find(job_id);
    if (it == active_.end() || it->second->run != rendered.run) return;  // cancelled meanwhile
    Job& job = *it->second;
    if (!result_path.ok()) {
        FailJob(job, absl::StrCat("writing the result: ", result_path.status().message()));
        return;
    }
    job.MoveTo(clock_(), JobState::kSucceeded);
    job.record.result_path = *result_path;
    Log()->info("job={} succeeded: {} samples -> {}", job_id, job.record.stats.samples,
                *result_path);
    EndJob(job);
}

uint64_t Scheduler::Save(Job& job, const std::vector<int>& drop_results) {
    // Derived, so that the record cannot disagree with the execution and the task states.
    job.Sync();
    const uint64_t ticket = drop_results.empty()
                                ? store_.QueuePut(job.record)
                                : store_.QueuePutDropping(job.record, drop_results);
    ++version_;
    changed_.notify_all();
    return ticket;
}

void Scheduler::Announce(Job& job) {
    job.Sync();
    ++version_;
    changed_.notify_all();
}

uint64_t Scheduler::WaitForChange(uint64_t version, absl::Time deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_until(lock, absl::ToChronoTime(deadline),
                        [&] { return version_ != version || shutdown_; });
    return version_;
}

Scheduler::EndWait Scheduler::WaitForEnd(const std::string& job_id, absl::Time deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto ended = [&] { return !active_.count(job_id) && !ended_.IsSettling(job_id); };
    // A shutdown ends the wait for a job still queued or running; one whose end is settling
    // settles within moments (the store outlives the service), and its end is what the client
    // must hear.
    const auto stopped = [&] { return shutdown_ && active_.count(job_id); };
    settled_.wait_until(lock, absl::ToChronoTime(deadline), [&] { return ended() || stopped(); });
    if (ended()) return EndWait::kEnded;
    return stopped() ? EndWait::kShutdown : EndWait::kRunning;
}

void Scheduler::Shutdown() {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
    changed_.notify_all();
    settled_.notify_all();
}

}  // namespace lf
