#include "lf/wire/stored_job.h"

#include <optional>

#include "lf/wire/conversions.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

using lf::FromProto;  // the conversions of lf/wire/conversions.h, beside the two below
using lf::ToProto;

// Unix microseconds; absl::InfinitePast (not yet) as unset.
std::optional<int64_t> UnixMicros(absl::Time t) {
    if (t == absl::InfinitePast()) return std::nullopt;
    return absl::ToUnixMicros(t);
}

void ToProto(const JobSpec& spec, pb::StoredJobSpec* out) {
    out->set_name(spec.name);
    ToProto(spec.scene, out->mutable_scene());
    for (const BlobRef& f : spec.files) ToProto(f, out->add_files());
    pb::RenderParams* params = out->mutable_params();
    ToProto(spec, params);
    // The wire carries a method's own settings only; the spec keeps the others too.
    ToProto(spec.radiosity, params->mutable_radiosity());
    ToProto(spec.ppm, params->mutable_ppm());
    out->set_width(spec.plan.width);
    out->set_height(spec.plan.height);
    out->set_priority(spec.priority);
    out->set_scene_hash(spec.scene_hash);
    out->set_request_id(spec.request_id);
    out->set_owner(spec.owner);
    for (const std::string& tag : spec.tags) out->add_tags(tag);
    out->set_max_workers(spec.max_workers);
    out->set_max_attempts(spec.max_attempts);
    out->set_blocklist_after(spec.blocklist_after);
    for (const std::string& id : spec.after) out->add_after(id);
}

JobSpec FromProto(const pb::StoredJobSpec& s) {
    JobSpec spec;
    spec.name = s.name();
    spec.scene = FromProto(s.scene());
    for (const pb::SceneFile& f : s.files()) spec.files.push_back(FromProto(f));
    FromProto(s.params(), &spec);
    spec.plan.width = s.width();
    spec.plan.height = s.height();
    spec.priority = s.priority();
    spec.scene_hash = s.scene_hash();
    spec.request_id = s.request_id();
    spec.owner = s.owner();
    spec.tags.assign(s.tags().begin(), s.tags().end());
    spec.max_workers = s.max_workers();
    if (s.max_attempts() != 0) spec.max_attempts = s.max_attempts();
    if (s.blocklist_after() != 0) spec.blocklist_after = s.blocklist_after();
    spec.after.assign(s.after().begin(), s.after().end());
    return spec;
}

}  // namespace

void ToProto(const JobRecord& job, pb::StoredJob* out) {
    out->set_id(job.id);
    out->set_seq(job.seq);
    ToProto(job.spec, out->mutable_spec());
    out->set_state(JobStateName(job.state));
    out->set_error(job.error);
    out->set_last_error(job.last_error);
    if (auto us = UnixMicros(job.submitted)) out->set_submitted_unix_us(*us);
    if (auto us = UnixMicros(job.started)) out->set_started_unix_us(*us);
    if (auto us = UnixMicros(job.finished)) out->set_finished_unix_us(*us);
    out->set_tasks_total(job.tasks_total);
    out->set_tasks_done(job.tasks_done);
    out->set_tasks_running(job.tasks_running);
    out->set_retries(job.retries);
    out->set_tasks_leased(job.tasks_leased);
    out->set_samples(job.stats.samples);
    out->set_rays(job.stats.rays);
    out->set_invalid_samples(job.stats.invalid_samples);
    out->set_result_path(job.result_path);
    for (const FrameProgress& frame : job.frames) {
        pb::StoredFrame* f = out->add_frames();
        f->set_frame(frame.frame);
        f->set_tasks_done(frame.tasks_done);
        f->set_tasks_total(frame.tasks_total);
        f->set_done(frame.done);
        f->set_result_path(frame.result_path);
        f->set_render_seconds(frame.times.render_seconds);
        f->set_cpu_seconds(frame.times.cpu_seconds);
    }
    for (const WorkerFailures& w : job.worker_failures) {
        pb::StoredWorkerFailures* f = out->add_worker_failures();
        f->set_worker(w.worker);
        f->set_failures(w.failures);
        f->set_last_error(w.last_error);
    }
    out->set_paused(job.paused);
    out->set_paused_for_us(absl::ToInt64Microseconds(job.paused_for));
    if (job.paused_at != absl::InfinitePast())
        out->set_paused_at_unix_us(absl::ToUnixMicros(job.paused_at));
    out->set_render_seconds(job.times.render_seconds);
    out->set_cpu_seconds(job.times.cpu_seconds);
}

absl::StatusOr<JobRecord> FromProto(const pb::StoredJob& s) {
    const absl::StatusOr<JobState> state = JobStateFromName(s.state());
    if (!state.ok()) return state.status();
    const auto time = [](bool has, int64_t us) {
        return has ? absl::FromUnixMicros(us) : absl::InfinitePast();
    };
    JobRecord job;
    job.id = s.id();
    job.seq = s.seq();
    job.spec = FromProto(s.spec());
    job.state = *state;
    job.error = s.error();
    job.last_error = s.last_error();
    job.submitted = time(s.has_submitted_unix_us(), s.submitted_unix_us());
    job.started = time(s.has_started_unix_us(), s.started_unix_us());
    job.finished = time(s.has_finished_unix_us(), s.finished_unix_us());
    job.tasks_total = s.tasks_total();
    job.tasks_done = s.tasks_done();
    job.tasks_running = s.tasks_running();
    job.retries = s.retries();
    job.tasks_leased = s.tasks_leased();
    job.stats.samples = s.samples();
    job.stats.rays = s.rays();
    job.stats.invalid_samples = s.invalid_samples();
    job.result_path = s.result_path();
    for (const pb::StoredFrame& f : s.frames()) {
        job.frames.push_back({f.frame(),
                              f.tasks_done(),
                              f.tasks_total(),
                              f.done(),
                              f.result_path(),
                              {f.render_seconds(), f.cpu_seconds()}});
    }
    for (const pb::StoredWorkerFailures& w : s.worker_failures()) {
        job.worker_failures.push_back({w.worker(), w.failures(), w.last_error()});
    }
    job.paused = s.paused();
    // A hostile or damaged record's negative time would lengthen the limit: read as none.
    job.paused_for = absl::Microseconds(std::max<int64_t>(0, s.paused_for_us()));
    if (s.has_paused_at_unix_us()) job.paused_at = absl::FromUnixMicros(s.paused_at_unix_us());
    job.times = {s.render_seconds(), s.cpu_seconds()};
    return job;
}

void ToProto(const TaskHistory& history, pb::StoredTaskHistory* out) {
    out->set_attempts(history.attempts);
    out->set_failures(history.failures);
    out->set_worker(history.worker);
    if (auto us = UnixMicros(history.leased)) out->set_leased_unix_us(*us);
    if (auto us = UnixMicros(history.finished)) out->set_finished_unix_us(*us);
    out->set_render_seconds(history.times.render_seconds);
    out->set_cpu_seconds(history.times.cpu_seconds);
    out->set_samples(history.samples);
    if (history.frame) out->set_frame(*history.frame);
}

TaskHistory FromProto(const pb::StoredTaskHistory& s) {
    TaskHistory history;
    history.attempts = s.attempts();
    history.failures = s.failures();
    history.worker = s.worker();
    if (s.has_leased_unix_us()) history.leased = absl::FromUnixMicros(s.leased_unix_us());
    if (s.has_finished_unix_us()) history.finished = absl::FromUnixMicros(s.finished_unix_us());
    history.times = {s.render_seconds(), s.cpu_seconds()};
    history.samples = s.samples();
    if (s.has_frame()) history.frame = s.frame();
    return history;
}

}  // namespace lf
