#include "lf/wire/conversions.h"

#include <memory>
#include <optional>

#include "lf/job/method_registry.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

int64_t UnixMillis(absl::Time t) { return t == absl::InfinitePast() ? 0 : absl::ToUnixMillis(t); }

pb::PixelFilterType ToProto(PixelFilter::Type type) {
    switch (type) {
        case PixelFilter::Type::kBox:
            return pb::FILTER_BOX;
        case PixelFilter::Type::kGaussian:
            return pb::FILTER_GAUSSIAN;
        case PixelFilter::Type::kBlackmanHarris:
            return pb::FILTER_BLACKMAN_HARRIS;
    }
    return pb::FILTER_UNSET;
}

// The filter `--filter` asked for, or nullopt for the scene's own. JobService refuses a type
// this build does not know before converting, and workers are leased tasks only by a
// coordinator of their own build (lf::kBuildVersion), so no other value arrives here.
std::optional<PixelFilter> FilterFromProto(const pb::RenderParams& p) {
    switch (p.filter_type()) {
        case pb::FILTER_BOX:
            return PixelFilter{PixelFilter::Type::kBox, p.filter_width()};
        case pb::FILTER_GAUSSIAN:
            return PixelFilter{PixelFilter::Type::kGaussian, p.filter_width()};
        case pb::FILTER_BLACKMAN_HARRIS:
            return PixelFilter{PixelFilter::Type::kBlackmanHarris, p.filter_width()};
        default:
            return std::nullopt;
    }
}

pb::SamplerType ToProto(SamplerType type) {
    return type == SamplerType::kSobol ? pb::SAMPLER_SOBOL : pb::SAMPLER_INDEPENDENT;
}

// JobService refuses values this build does not know before converting, as for the filter.
SamplerType FromProto(pb::SamplerType type) {
    return type == pb::SAMPLER_SOBOL ? SamplerType::kSobol : SamplerType::kIndependent;
}

pb::LightStrategy ToProto(LightStrategy strategy) {
    return strategy == LightStrategy::kBvh ? pb::LIGHT_STRATEGY_BVH : pb::LIGHT_STRATEGY_POWER;
}

// Refused by JobService when unknown, as the sampler is.
LightStrategy FromProto(pb::LightStrategy strategy) {
    return strategy == pb::LIGHT_STRATEGY_BVH ? LightStrategy::kBvh : LightStrategy::kPower;
}

}  // namespace

void ToProto(const BlobRef& ref, pb::SceneFile* out) {
    out->set_path(ref.path);
    out->set_hash(ref.hash);
    out->set_size(ref.size);
}

BlobRef FromProto(const pb::SceneFile& f) { return {f.path(), f.hash(), f.size()}; }

void ToProto(const RadiositySettings& s, pb::RadiosityParams* out) {
    out->set_patches(s.patches);
    out->set_patch_size(s.patch_size);
    out->set_solver(s.solver);
    out->set_tolerance(s.tolerance);
    out->set_max_iterations(s.max_iterations);
    out->set_display(s.display);
    out->set_sweep_tasks(s.sweep_tasks);
    out->set_max_patches(s.max_patches);
    out->set_form(s.form);
    out->set_link_error(s.link_error);
}

RadiositySettings FromProto(const pb::RadiosityParams& p) {
    RadiositySettings s{p.patches(),   p.patch_size(),     p.solver(),
                        p.tolerance(), p.max_iterations(), p.display()};
    if (p.sweep_tasks() != 0) s.sweep_tasks = p.sweep_tasks();
    s.max_patches = p.max_patches();
    // Unset by clients from before hierarchical radiosity: the flat method they knew.
    if (!p.form().empty()) s.form = p.form();
    if (p.link_error() != 0) s.link_error = p.link_error();
    return s;
}

void ToProto(const PhotonSettings& s, pb::PhotonParams* out) {
    out->set_photons_per_pass(s.photons_per_pass);
    out->set_initial_radius(s.initial_radius);
    out->set_alpha(s.alpha);
}

void ToProto(const JobSpec& spec, pb::RenderParams* out) {
    out->set_spp(spec.plan.spp);
    out->set_seed(spec.seed);
    out->set_max_depth(spec.max_depth);
    out->set_tile(spec.plan.tile);
    out->set_passes(spec.plan.passes);
    out->set_method(spec.method);
    // Each method's own settings only; an unknown name the coordinator refuses carries none.
    const std::optional<Method> method = FindMethod(spec.method);
    const MethodInfo* info = method ? &Info(*method) : nullptr;
    if (info && info->work == WorkKind::kRadiosity) {
        ToProto(spec.radiosity, out->mutable_radiosity());
    }
    if (info && info->splat_plan == SplatPlanKind::kPhotonPasses) {
        ToProto(spec.ppm, out->mutable_ppm());
    }
    out->set_target_error(spec.adaptive.target_error);
    out->set_time_limit_seconds(spec.adaptive.time_limit);
    out->set_max_spp(spec.adaptive.max_spp);
    out->set_noise_threshold(spec.adaptive.noise_threshold);
    out->set_camera(spec.scene_options.camera);
    out->set_width(spec.scene_options.width);
    out->set_height(spec.scene_options.height);
    out->set_sky(spec.scene_options.sky);
    out->set_clamp(spec.clamp);
    out->set_aovs(spec.aovs);
    out->set_sampler(ToProto(spec.sampler));
    out->set_light_strategy(ToProto(spec.light_strategy));
    if (const std::optional<PixelFilter>& filter = spec.scene_options.filter) {
        out->set_filter_type(ToProto(filter->type));
        out->set_filter_width(filter->width);
    }
    if (const std::optional<FrameRange>& frames = spec.shot.frames) {
        pb::ShotParams* shot = out->mutable_shot();
        shot->set_first(frames->first);
        shot->set_last(frames->last);
        shot->set_step(frames->step);
        shot->set_fps(spec.shot.fps);
        shot->set_shutter(spec.shot.shutter);
        shot->set_chunk(spec.shot.chunk);
    }
}

void FromProto(const pb::RenderParams& p, JobSpec* spec) {
    spec->plan.spp = p.spp();
    spec->plan.tile = p.tile();
    spec->plan.passes = p.passes();
    spec->seed = p.seed();
    spec->max_depth = p.max_depth();
    if (!p.method().empty()) spec->method = p.method();
    if (p.has_radiosity()) spec->radiosity = FromProto(p.radiosity());
    if (p.has_ppm()) {  // zero fields keep the defaults
        if (p.ppm().photons_per_pass() != 0)
            spec->ppm.photons_per_pass = p.ppm().photons_per_pass();
        spec->ppm.initial_radius = p.ppm().initial_radius();
        if (p.ppm().alpha() != 0) spec->ppm.alpha = p.ppm().alpha();
    }
    spec->adaptive.target_error = p.target_error();
    spec->adaptive.time_limit = p.time_limit_seconds();
    if (p.max_spp() != 0) spec->adaptive.max_spp = p.max_spp();
    spec->adaptive.noise_threshold = p.noise_threshold();
    spec->scene_options = {p.camera(), p.width(), p.height(), FilterFromProto(p), p.sky()};
    spec->clamp = p.clamp();
    spec->aovs = p.aovs();
    spec->sampler = FromProto(p.sampler());
    spec->light_strategy = FromProto(p.light_strategy());
    spec->shot = {};
    if (p.has_shot()) {  // zero fields keep the defaults; CheckJobSettings refuses the rest
        const pb::ShotParams& shot = p.shot();
        spec->shot.frames = FrameRange{shot.first(), shot.last(), shot.step() ? shot.step() : 1};
        if (shot.fps() != 0) spec->shot.fps = shot.fps();
        spec->shot.shutter = shot.shutter();
        if (shot.chunk() != 0) spec->shot.chunk = shot.chunk();
    }
}

void ToProto(const JobSpec& spec, pb::SubmitJobRequest* out) {
    ToProto(spec.scene, out->mutable_scene());
    for (const BlobRef& f : spec.files) ToProto(f, out->add_files());
    ToProto(spec, out->mutable_params());
    out->set_priority(spec.priority);
    out->set_name(spec.name);
    out->set_request_id(spec.request_id);
    for (const std::string& tag : spec.tags) out->add_tags(tag);
    out->set_max_workers(spec.max_workers);
    out->set_max_attempts(spec.max_attempts);
    out->set_blocklist_after(spec.blocklist_after);
    for (const std::string& id : spec.after) out->add_after(id);
}

JobSpec FromProto(const pb::SubmitJobRequest& r) {
    JobSpec spec;
    spec.name = r.name().empty() ? r.scene().path() : r.name();
    spec.request_id = r.request_id();
    spec.scene = FromProto(r.scene());
    for (const pb::SceneFile& f : r.files()) spec.files.push_back(FromProto(f));
    FromProto(r.params(), &spec);
    spec.priority = r.priority();
    spec.tags.assign(r.tags().begin(), r.tags().end());
    spec.max_workers = r.max_workers();
    if (r.max_attempts() != 0) spec.max_attempts = r.max_attempts();
    if (r.blocklist_after() != 0) spec.blocklist_after = r.blocklist_after();
    spec.after.assign(r.after().begin(), r.after().end());
    return spec;
}

pb::Job::State ToProto(JobState s) {
    switch (s) {
        case JobState::kQueued:
            return pb::Job::QUEUED;
        case JobState::kRunning:
            return pb::Job::RUNNING;
        case JobState::kSucceeded:
            return pb::Job::SUCCEEDED;
        case JobState::kFailed:
            return pb::Job::FAILED;
        case JobState::kCancelled:
            return pb::Job::CANCELLED;
    }
    return pb::Job::STATE_UNSPECIFIED;
}

JobState FromProto(pb::Job::State s) {
    switch (s) {
        case pb::Job::RUNNING:
            return JobState::kRunning;
        case pb::Job::SUCCEEDED:
            return JobState::kSucceeded;
        case pb::Job::FAILED:
            return JobState::kFailed;
        case pb::Job::CANCELLED:
            return JobState::kCancelled;
        default:
            return JobState::kQueued;
    }
}

void ToProto(const JobRecord& job, pb::Job* out) {
    out->set_id(job.id);
    out->set_name(job.spec.name);
    out->set_state(ToProto(job.state));
    out->set_error(job.error);
    ToProto(job.spec, out->mutable_params());
    out->set_priority(job.spec.priority);
    out->set_width(job.spec.plan.width);
    out->set_height(job.spec.plan.height);
    out->set_scene_hash(job.spec.scene_hash);
    out->set_tasks_total(job.tasks_total);
    out->set_tasks_done(job.tasks_done);
    out->set_tasks_running(job.tasks_running);
    out->set_samples(job.stats.samples);
    out->set_rays(job.stats.rays);
    out->set_invalid_samples(job.stats.invalid_samples);
    out->set_submitted_unix_ms(UnixMillis(job.submitted));
    out->set_started_unix_ms(UnixMillis(job.started));
    out->set_finished_unix_ms(UnixMillis(job.finished));
    out->set_retries(job.retries);
    out->set_tasks_leased(job.tasks_leased);
    out->set_last_error(job.last_error);
    out->set_owner(job.spec.owner);
    if (job.spec.shot.frames) {
        out->set_frames_done(job.frames_done());
        out->set_frames_total(job.spec.shot.frames->count());
    }
    for (const FrameProgress& frame : job.frames) {
        pb::FrameProgress* f = out->add_frames();
        f->set_frame(frame.frame);
        f->set_tasks_done(frame.tasks_done);
        f->set_tasks_total(frame.tasks_total);
        f->set_done(frame.done);
        f->set_render_seconds(frame.times.render_seconds);
        f->set_cpu_seconds(frame.times.cpu_seconds);
    }
    for (const std::string& tag : job.spec.tags) out->add_tags(tag);
    out->set_max_workers(job.spec.max_workers);
    out->set_waiting_reason(job.waiting_reason);
    for (const WorkerFailures& w : job.Blocklisted()) {
        pb::BlockedWorker* b = out->add_blocklist();
        b->set_worker(w.worker);
        b->set_failures(w.failures);
        b->set_last_error(w.last_error);
    }
    out->set_max_attempts(job.spec.max_attempts);
    out->set_blocklist_after(job.spec.blocklist_after);
    out->set_paused(job.paused);
    out->set_render_seconds(job.times.render_seconds);
    out->set_cpu_seconds(job.times.cpu_seconds);
    for (const std::string& id : job.spec.after) out->add_after(id);
    for (const std::string& id : job.waiting_for) out->add_waiting_for(id);
}

void ToProto(const TaskAssignment& task, pb::Task* out) {
    out->set_lease_id(task.lease_id);
    out->set_job_id(task.job_id);
    out->set_task_index(task.task.index);
    ToProto(task.spec.scene, out->mutable_scene());
    for (const BlobRef& f : task.spec.files) ToProto(f, out->add_files());
    ToProto(task.spec, out->mutable_params());
    out->set_x0(task.task.rect.x0);
    out->set_y0(task.task.rect.y0);
    out->set_width(task.task.rect.width);
    out->set_height(task.task.rect.height);
    out->set_sample_begin(task.task.sample_begin);
    out->set_sample_end(task.task.sample_end);
    out->set_active_pixels(task.task.active_pixels);
    if (task.sweep >= 0) {
        out->set_kind(pb::Task::RADIOSITY_SWEEP);
        out->set_sweep(task.sweep);
        if (!task.chunks.empty()) out->set_chunk(task.chunks.front());
        for (size_t k = 1; k < task.chunks.size(); ++k) out->add_more_chunks(task.chunks[k]);
    } else if (UsesSplatPlan(task.spec.method)) {
        out->set_kind(pb::Task::FRAME);
        out->set_path_begin(task.path_begin);
        out->set_path_end(task.path_end);
    }
    out->set_radiosity_hash(task.radiosity_hash);
    if (task.radiosity_input) out->set_radiosity_input(*task.radiosity_input);
    if (task.frame) out->set_frame(*task.frame);
    for (const TaskAssignment::Part& part : task.parts) {
        pb::TaskPart* p = out->add_parts();
        p->set_frame(part.frame);
        p->set_x0(part.task.rect.x0);
        p->set_y0(part.task.rect.y0);
        p->set_width(part.task.rect.width);
        p->set_height(part.task.rect.height);
        p->set_sample_begin(part.task.sample_begin);
        p->set_sample_end(part.task.sample_end);
        p->set_path_begin(part.path_begin);
        p->set_path_end(part.path_end);
    }
    out->set_heartbeat_interval_ms(int(absl::ToInt64Milliseconds(task.heartbeat_interval)));
    out->set_lease_ms(int(absl::ToInt64Milliseconds(task.lease)));
}

TaskAssignment FromProto(const pb::Task& t) {
    TaskAssignment task;
    task.lease_id = t.lease_id();
    task.job_id = t.job_id();
    task.task.index = t.task_index();
    task.spec.scene = FromProto(t.scene());
    for (const pb::SceneFile& f : t.files()) task.spec.files.push_back(FromProto(f));
    FromProto(t.params(), &task.spec);
    if (t.kind() == pb::Task::RADIOSITY_SWEEP) {
        task.sweep = t.sweep();
        task.chunks.push_back(t.chunk());
        task.chunks.insert(task.chunks.end(), t.more_chunks().begin(), t.more_chunks().end());
    }
    if (t.kind() == pb::Task::FRAME) {
        task.path_begin = t.path_begin();
        task.path_end = t.path_end();
    }
    task.radiosity_hash = t.radiosity_hash();
    if (!t.radiosity_input().empty()) {
        task.radiosity_input = std::make_shared<const std::string>(t.radiosity_input());
    }
    task.task.rect = {t.x0(), t.y0(), t.width(), t.height()};
    task.task.sample_begin = t.sample_begin();
    task.task.sample_end = t.sample_end();
    task.task.active_pixels = t.active_pixels();
    if (t.has_frame()) task.frame = t.frame();
    for (const pb::TaskPart& p : t.parts()) {
        TaskAssignment::Part part{
            .frame = p.frame(), .path_begin = p.path_begin(), .path_end = p.path_end()};
        part.task.index = t.task_index();
        part.task.rect = {p.x0(), p.y0(), p.width(), p.height()};
        part.task.sample_begin = p.sample_begin();
        part.task.sample_end = p.sample_end();
        task.parts.push_back(part);
    }
    if (t.heartbeat_interval_ms() > 0) {
        task.heartbeat_interval = absl::Milliseconds(t.heartbeat_interval_ms());
    }
    if (t.lease_ms() > 0) task.lease = absl::Milliseconds(t.lease_ms());
    return task;
}

pb::WorkerInfo::State ToProto(WorkerState state) {
    switch (state) {
        case WorkerState::kIdle:
            return pb::WorkerInfo::IDLE;
        case WorkerState::kBusy:
            return pb::WorkerInfo::BUSY;
        case WorkerState::kDisabled:
            return pb::WorkerInfo::DISABLED;
        case WorkerState::kDraining:
            return pb::WorkerInfo::DRAINING;
        case WorkerState::kDrained:
            return pb::WorkerInfo::DRAINED;
        case WorkerState::kOffline:
            return pb::WorkerInfo::OFFLINE;
    }
    return pb::WorkerInfo::STATE_UNSPECIFIED;
}

void ToProto(const WorkerStatus& worker, pb::WorkerInfo* out) {
    out->set_id(worker.id);
    out->set_name(worker.name);
    out->set_address(worker.address);
    out->set_version(worker.version);
    out->set_state(ToProto(StateOf(worker)));
    out->set_job_id(worker.job_id);
    out->set_task_index(worker.task);
    out->set_seconds_since_seen(absl::ToDoubleSeconds(worker.since_seen));
    for (const std::string& tag : worker.tags) out->add_tags(tag);
    out->set_last_seen_unix_ms(absl::ToUnixMillis(worker.last_seen));
}

namespace {

// Unix milliseconds, 0 for a time not reached yet.
int64_t UnixMs(absl::Time t) { return t == absl::InfinitePast() ? 0 : absl::ToUnixMillis(t); }

pb::TaskInfo::State ToProto(TaskStatus::State state) {
    switch (state) {
        case TaskStatus::State::kWaiting:
            return pb::TaskInfo::WAITING;
        case TaskStatus::State::kQueued:
            return pb::TaskInfo::QUEUED;
        case TaskStatus::State::kRunning:
            return pb::TaskInfo::RUNNING;
        case TaskStatus::State::kDone:
            return pb::TaskInfo::DONE;
        case TaskStatus::State::kDropped:
            return pb::TaskInfo::DROPPED;
    }
    return pb::TaskInfo::STATE_UNSPECIFIED;
}

pb::TaskInfo::Kind ToProto(TaskKind kind) {
    switch (kind) {
        case TaskKind::kTile:
            return pb::TaskInfo::TILE;
        case TaskKind::kSplat:
            return pb::TaskInfo::FRAME;
        case TaskKind::kRadiositySweep:
            return pb::TaskInfo::RADIOSITY_SWEEP;
    }
    return pb::TaskInfo::KIND_UNSPECIFIED;
}

}  // namespace

void ToProto(const TaskStatus& task, pb::TaskInfo* out) {
    out->set_index(task.index);
    out->set_state(ToProto(task.state));
    out->set_kind(ToProto(task.kind));
    out->set_x(task.x);
    out->set_y(task.y);
    out->set_width(task.width);
    out->set_height(task.height);
    out->set_samples(task.samples);
    out->set_attempts(task.attempts);
    out->set_failures(task.failures);
    out->set_worker(task.worker);
    out->set_leased_unix_ms(UnixMs(task.leased));
    out->set_finished_unix_ms(UnixMs(task.finished));
    out->set_seconds(absl::ToDoubleSeconds(task.duration));
    out->set_last_error(task.last_error);
    out->set_log_lines(task.log_lines);
    for (int frame : task.frames) out->add_frames(frame);
    out->set_render_seconds(task.times.render_seconds);
    out->set_cpu_seconds(task.times.cpu_seconds);
}

void ToProto(const FarmStats& stats, pb::GetStatsResponse* out) {
    if (stats.since != absl::InfinitePast())
        out->set_since_unix_ms(absl::ToUnixMillis(stats.since));
    for (const OwnerStats& o : stats.owners) {
        pb::OwnerStats* p = out->add_owners();
        p->set_owner(o.owner);
        p->set_jobs_succeeded(o.succeeded);
        p->set_jobs_failed(o.failed);
        p->set_jobs_cancelled(o.cancelled);
        p->set_jobs_active(o.active);
        p->set_tasks(o.tasks);
        p->set_samples(o.samples);
        p->set_cpu_seconds(o.times.cpu_seconds);
        p->set_render_seconds(o.times.render_seconds);
    }
    for (const WorkerStats& w : stats.workers) {
        pb::WorkerStats* p = out->add_workers();
        p->set_worker(w.worker);
        p->set_tasks(w.tasks);
        p->set_failures(w.failures);
        p->set_cpu_seconds(w.times.cpu_seconds);
        p->set_render_seconds(w.times.render_seconds);
    }
}

void ToProto(const TaskLogLine& line, pb::TaskLogLine* out) {
    out->set_seq(line.seq);
    out->set_task_index(line.task);
    out->set_attempt(line.attempt);
    out->set_worker(line.worker);
    out->set_unix_ms(absl::ToUnixMillis(line.time));
    out->set_level(line.level);
    out->set_text(line.text);
}

void ToProto(const TaskLogLine& line, pb::WorkerLogLine* out) {
    out->set_unix_ms(absl::ToUnixMillis(line.time));
    out->set_level(line.level);
    out->set_text(line.text);
}

TaskLogLine FromProto(const pb::WorkerLogLine& line) {
    TaskLogLine out;
    out.time = absl::FromUnixMillis(line.unix_ms());
    out.level = line.level();
    out.text = line.text();
    return out;
}

void ToProto(const RadiosityFigures& f, pb::RadiosityReport* out) {
    out->set_patches(f.patches);
    out->set_unknowns(f.unknowns);
    out->set_patch_size(f.patch_size);
    out->set_loaded(f.loaded);
    out->set_iterations(f.iterations);
    out->set_residual(f.residual);
    out->set_form_factor_seconds(f.form_factor_seconds);
    out->set_solve_seconds(f.solve_seconds);
    out->set_estimated_error(f.estimated_error);
    out->set_mean_estimated_error(f.mean_estimated_error);
    out->set_refine_passes(f.refine_passes);
    out->set_coarse_patches(f.coarse_patches);
    out->set_budget_reached(f.budget_reached);
    out->set_finest_above_target(f.finest_above_target);
    out->set_links(f.links);
    out->set_links_per_side(f.links_per_side);
    out->set_link_bytes(f.link_bytes);
    out->set_solver_bytes(f.solver_bytes);
}

RadiosityFigures FromProto(const pb::RadiosityReport& r) {
    RadiosityFigures f;
    f.patches = r.patches();
    f.unknowns = r.unknowns();
    f.patch_size = r.patch_size();
    f.loaded = r.loaded();
    f.iterations = r.iterations();
    f.residual = r.residual();
    f.form_factor_seconds = r.form_factor_seconds();
    f.solve_seconds = r.solve_seconds();
    f.estimated_error = r.estimated_error();
    f.mean_estimated_error = r.mean_estimated_error();
    f.refine_passes = r.refine_passes();
    f.coarse_patches = r.coarse_patches();
    f.budget_reached = r.budget_reached();
    f.finest_above_target = r.finest_above_target();
    f.links = r.links();
    f.links_per_side = r.links_per_side();
    f.link_bytes = r.link_bytes();
    f.solver_bytes = r.solver_bytes();
    return f;
}

}  // namespace lf
