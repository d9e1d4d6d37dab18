#include "lf/server/dashboard.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "lf/core/log.h"
#include "lf/job/shot.h"
#include "lf/server/listen_policy.h"
#include "lf/server/preview_channels.h"
#include "lf/server/web_assets.h"

namespace lf {

namespace {

using Json = nlohmann::json;

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("dashboard"); }

constexpr char kJsonType[] = "application/json";
constexpr int kDefaultJobs = 50, kMaxJobs = 200;
// Jobs one list request reads at most to fill a filtered page; it goes on from there when asked.
constexpr size_t kJobsReadAtOnce = 200, kMaxJobsScanned = 5000;
constexpr size_t kMaxFilterBytes = 256;
constexpr int kDefaultTasks = 1000, kMaxTasks = 10000;
constexpr double kMaxExposure = 8;  // stops either way
constexpr int kDefaultLogLines = 200, kMaxLogLines = 1000;
constexpr size_t kMaxJobIdBytes = 64;

// Nothing but the server's own files, and no page may frame the dashboard.
const std::vector<std::pair<std::string, std::string>>& SecurityHeaders() {
    static const std::vector<std::pair<std::string, std::string>> headers = {
        {"Content-Security-Policy",
         "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self'; "
         "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"},
        {"X-Content-Type-Options", "nosniff"},
        {"Referrer-Policy", "no-referrer"},
    };
    return headers;
}

HttpAnswer JsonAnswer(int status, const Json& body) {
    HttpAnswer a{status, kJsonType, body.dump(), {{"Cache-Control", "no-store"}}};
    return a;
}

int HttpStatusOf(const absl::Status& s) {
    switch (s.code()) {
        case absl::StatusCode::kInvalidArgument:
        case absl::StatusCode::kOutOfRange:
            return 400;
        case absl::StatusCode::kUnauthenticated:
            return 401;
        case absl::StatusCode::kPermissionDenied:
            return 403;
        case absl::StatusCode::kNotFound:
            return 404;
        case absl::StatusCode::kFailedPrecondition:
        case absl::StatusCode::kAlreadyExists:
            return 409;
        case absl::StatusCode::kResourceExhausted:
            return 429;
        case absl::StatusCode::kUnavailable:
            return 503;
        default:
            return 500;
    }
}

HttpAnswer ErrorAnswer(const absl::Status& s) {
    return JsonAnswer(HttpStatusOf(s), {{"error", std::string(s.message())}});
}

HttpAnswer NotFoundAnswer() { return ErrorAnswer(absl::NotFoundError("not found")); }

// Milliseconds since the Unix epoch; null for a time that has not come (InfinitePast).
Json UnixMs(absl::Time t) {
    return t == absl::InfinitePast() ? Json(nullptr) : Json(absl::ToUnixMillis(t));
}

// Seconds left at the pace of the tasks merged so far; null before the first one.
Json EtaSeconds(const JobRecord& job, absl::Time now) {
    if (IsFinal(job.state) || job.tasks_done == 0 || job.started == absl::InfinitePast()) {
        return nullptr;
    }
    const double elapsed = absl::ToDoubleSeconds(now - job.started);
    return elapsed * (job.tasks_total - job.tasks_done) / job.tasks_done;
}

// A shot's range and how far it is; null for a still. `current`: the first frame not done.
Json ShotJson(const JobRecord& job) {
    if (!job.spec.shot.frames) return nullptr;
    const FrameRange& range = *job.spec.shot.frames;
    int current = range.last;
    for (const FrameProgress& f : job.frames) {
        if (!f.done) {
            current = f.frame;
            break;
        }
    }
    if (job.frames.empty()) current = range.first;
    return {{"first", range.first},
            {"last", range.last},
            {"step", range.step},
            {"fps", job.spec.shot.fps},
            {"shutter", job.spec.shot.shutter},
            {"chunk", job.spec.shot.chunk},
            {"frames_total", range.count()},
            {"frames_done", job.frames_done()},
            {"current", current}};
}

// The workers blocklisted from the job (lf/server/blocklist.h).
Json BlocklistJson(const JobRecord& job) {
    Json list = Json::array();
    for (const WorkerFailures& w : job.Blocklisted()) {
        list.push_back(
            {{"worker", w.worker}, {"failures", w.failures}, {"last_error", w.last_error}});
    }
    return list;
}

Json JobJson(const JobRecord& job, absl::Time now) {
    return {
        {"id", job.id},
        {"seq", job.seq},
        {"name", job.spec.name},
        {"owner", job.spec.owner},
        {"method", job.spec.method},
        {"state", JobStateName(job.state)},
        {"priority", job.spec.priority},
        {"width", job.spec.plan.width},
        {"height", job.spec.plan.height},
        {"spp", job.spec.plan.spp},
        {"tasks_total", job.tasks_total},
        {"tasks_done", job.tasks_done},
        {"tasks_running", job.tasks_running},
        {"retries", job.retries},
        {"submitted_ms", UnixMs(job.submitted)},
        {"started_ms", UnixMs(job.started)},
        {"finished_ms", UnixMs(job.finished)},
        {"eta_s", EtaSeconds(job, now)},
        {"error", job.error},
        {"last_error", job.last_error},
        {"shot", ShotJson(job)},
        // Job management (issue 30).
        {"max_attempts", job.spec.max_attempts},
        {"blocklist_after", job.spec.blocklist_after},
        {"blocklist", BlocklistJson(job)},
        {"paused", job.paused},
        // History (issue 30): summed over the merged tasks, as their workers measured them.
        {"render_s", job.times.render_seconds},
        {"cpu_s", job.times.cpu_seconds},
    };
}

// A frame as the strip shows it: done, rendering (a task of it runs or has merged), queued, or
// the state of a shot that ended without it.
const char* FrameStateName(const FrameProgress& f, JobState job, bool running) {
    if (f.done) return "done";
    if (IsFinal(job)) return JobStateName(job);
    return running || f.tasks_done > 0 ? "rendering" : "queued";
}

// The frame's preview, its version in the query so that an image reloads only when it changed;
// null when there is none to show (nothing merged yet, or an unfinished frame of an ended shot).
Json FramePreviewUrl(const JobRecord& job, const FrameProgress& f) {
    if (f.result_path.empty() && (IsFinal(job.state) || (!f.done && f.tasks_done == 0))) {
        return nullptr;
    }
    return absl::StrCat("/api/jobs/", job.id, "/frames/", f.frame, "/preview.png?v=", f.tasks_done,
                        f.done ? "-done" : "");
}

// The version of a frame's preview: its merged tasks, and whether they are all.
std::string FramePreviewEtag(int tasks_done, bool done) {
    return absl::StrCat("\"frame-", tasks_done, done ? "-done" : "", "\"");
}

// A shot's frames from position `from` of its range, at most Dashboard::kFramesListed of them;
// `running`: the frames a running task renders.
Json FramesJson(const JobRecord& job, int from, const std::set<int>& running) {
    const FrameRange& range = *job.spec.shot.frames;
    Json frames = Json::array();
    for (int i = from; i < std::min(range.count(), from + Dashboard::kFramesListed); ++i) {
        FrameProgress f{.frame = range.at(i)};
        if (const FrameProgress* listed = FrameOf(job, f.frame)) f = *listed;
        frames.push_back({{"frame", f.frame},
                          {"state", FrameStateName(f, job.state, running.count(f.frame) > 0)},
                          {"tasks_done", f.tasks_done},
                          {"tasks_total", f.tasks_total},
                          {"render_s", f.times.render_seconds},
                          {"cpu_s", f.times.cpu_seconds},
                          {"preview", FramePreviewUrl(job, f)}});
    }
    return frames;
}

Json TaskJson(const TaskStatus& t) {
    return {
        {"index", t.index},
        {"state", TaskStatusName(t.state)},
        {"kind", TaskKindName(t.kind)},
        {"x", t.x},
        {"y", t.y},
        {"width", t.width},
        {"height", t.height},
        {"samples", t.samples},
        {"attempts", t.attempts},
        {"failures", t.failures},
        {"worker", t.worker},
        {"leased_ms", UnixMs(t.leased)},
        {"finished_ms", UnixMs(t.finished)},
        {"duration_ms", absl::ToInt64Milliseconds(t.duration)},
        {"last_error", t.last_error},
        {"log_lines", t.log_lines},
        {"frames", t.frames},
        {"render_s", t.times.render_seconds},
        {"cpu_s", t.times.cpu_seconds},
    };
}

Json AttributeJson(const ExrAttribute& value) {
    return std::visit(
        [](const auto& v) -> Json {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, ExrChromaticities>) {
                return {{"red", {v.red_x, v.red_y}},
                        {"green", {v.green_x, v.green_y}},
                        {"blue", {v.blue_x, v.blue_y}},
                        {"white", {v.white_x, v.white_y}}};
            } else {
                return v;
            }
        },
        value);
}

// A job id as the scheduler makes them ("job-" and hex); anything else names no job.
bool PlausibleJobId(const std::string& id) {
    return !id.empty() && id.size() <= kMaxJobIdBytes &&
           std::all_of(id.begin(), id.end(), [](char c) {
               return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
           });
}

// An integer query parameter within [lo, hi]; `fallback` when absent.
absl::StatusOr<int64_t> IntParam(const HttpRequest& request, const std::string& name,
                                 int64_t fallback, int64_t lo, int64_t hi) {
    std::optional<std::string> text = request.Query(name);
    if (!text) return fallback;
    int64_t value = 0;
    if (!absl::SimpleAtoi(*text, &value) || value < lo || value > hi) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": expected an integer in ", lo, "..", hi));
    }
    return value;
}

// A number query parameter within [lo, hi]; `fallback` when absent.
absl::StatusOr<double> DoubleParam(const HttpRequest& request, const std::string& name,
                                   double fallback, double lo, double hi) {
    std::optional<std::string> text = request.Query(name);
    if (!text) return fallback;
    double value = 0;
    if (!absl::SimpleAtod(*text, &value) || !(value >= lo && value <= hi)) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": expected a number in ", lo, "..", hi));
    }
    return value;
}

// A text filter parameter: "" when absent; InvalidArgument naming it when too long.
absl::StatusOr<std::string> FilterParam(const HttpRequest& request, const std::string& name) {
    std::string text = request.Query(name).value_or("");
    if (text.size() > kMaxFilterBytes) {
        return absl::InvalidArgumentError(
            absl::StrCat(name, ": at most ", kMaxFilterBytes, " bytes"));
    }
    return text;
}

// ?state=NAME of a task: one of TaskStatusName's; nullopt when absent or empty.
absl::StatusOr<std::optional<TaskStatus::State>> TaskStateParam(const HttpRequest& request) {
    const std::string text = request.Query("state").value_or("");
    if (text.empty()) return std::nullopt;
    std::vector<std::string> names;
    for (int i = 0; i <= int(TaskStatus::State::kDropped); ++i) {
        const auto state = TaskStatus::State(i);
        if (text == TaskStatusName(state)) return state;
        names.push_back(TaskStatusName(state));
    }
    return absl::InvalidArgumentError(absl::StrCat("state: no task state \"", LogSafe(text),
                                                   "\"; expected one of ",
                                                   absl::StrJoin(names, ", ")));
}

// A downloaded file's name: the job's id (a plausible one: no quotes), a shot's frame, `ext`.
std::string AttachmentHeader(const std::string& job_id, std::optional<int> frame,
                             const std::string& ext) {
    return absl::StrCat("attachment; filename=\"", job_id,
                        frame ? absl::StrCat("-frame", *frame) : "", ".", ext, "\"");
}

std::string ContentTypeOf(const std::string& name) {
    const std::string ext = name.substr(name.rfind('.') + 1);
    if (ext == "html") return "text/html; charset=utf-8";
    if (ext == "js") return "text/javascript; charset=utf-8";
    if (ext == "css") return "text/css; charset=utf-8";
    if (ext == "svg") return "image/svg+xml";
    return "application/octet-stream";
}

// A strong validator of an embedded file: FNV-1a of its bytes.
std::string EtagOf(std::string_view bytes) {
    uint64_t h = 14695981039346656037ull;
    for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
    return absl::StrCat("\"", absl::Hex(h), "\"");
}

// 304 when the client holds this version already.
bool NotModified(const HttpRequest& request, const std::string& etag) {
    std::optional<std::string> held = request.Header("if-none-match");
    return held && *held == etag;
}

HttpAnswer AssetAnswer(const HttpRequest& request, const std::string& name) {
    for (const WebAsset& asset : WebAssets()) {
        if (asset.name != name) continue;
        const std::string etag = EtagOf(asset.content);
        // Revalidated on every load (a new server build may change them); 304 is cheap.
        std::vector<std::pair<std::string, std::string>> headers = {{"Cache-Control", "no-cache"},
                                                                    {"ETag", etag}};
        if (NotModified(request, etag)) return {304, "", "", std::move(headers)};
        return {200, ContentTypeOf(name), std::string(asset.content), std::move(headers)};
    }
    return NotFoundAnswer();
}

// The value of cookie `name` in a Cookie header.
std::optional<std::string> CookieValue(const std::string& header, const std::string& name) {
    for (absl::string_view part : absl::StrSplit(header, ';')) {
        part = absl::StripAsciiWhitespace(part);
        if (absl::StartsWith(part, name + "=")) return std::string(part.substr(name.size() + 1));
    }
    return std::nullopt;
}

std::string SessionCookie(const std::string& value, bool tls, bool clear) {
    return absl::StrCat(Dashboard::kCookie, "=", value, "; Path=/; HttpOnly; SameSite=Strict",
                        tls ? "; Secure" : "", clear ? "; Max-Age=0" : "");
}

Json CallerJson(const Caller& caller, bool auth) {
    return {{"name", caller.name}, {"role", RoleName(caller.role)}, {"auth", auth}};
}

}  // namespace

Dashboard::Dashboard(Farm& farm, Authenticator& auth, DashboardOptions options)
    : farm_(farm), auth_(auth), options_(options) {}

HttpAnswer Dashboard::Serve(const HttpRequest& request) {
    HttpAnswer answer;
    if (absl::StartsWith(request.path, "/api/")) {
        answer = Api(request, request.path.substr(5));
    } else if (request.method != "GET") {
        answer = ErrorAnswer(absl::InvalidArgumentError("the pages are only read (GET)"));
        answer.status = 405;
    } else if (request.path == "/") {
        answer = AssetAnswer(request, "index.html");
    } else if (absl::StartsWith(request.path, "/web/")) {
        answer = AssetAnswer(request, request.path.substr(5));
    } else {
        answer = NotFoundAnswer();
    }
    const auto& security = SecurityHeaders();
    answer.headers.insert(answer.headers.end(), security.begin(), security.end());
    return answer;
}

absl::StatusOr<Caller> Dashboard::CallerOf(const HttpRequest& request) {
    if (!auth_.enabled() && !(IsLoopbackHost(request.remote_addr) &&
                              IsLoopbackHost(ListenHost(request.Header("host").value_or(""))))) {
        // Without tokens everyone is an admin: only this machine may be, through an address
        // that names it (a page of another site renamed to 127.0.0.1 names itself).
        return absl::PermissionDeniedError(
            "authentication is off (no tokens): the dashboard answers only this machine at "
            "localhost or 127.0.0.1; make a token (lightfarm-server token create) to open it to "
            "others");
    }
    std::optional<std::string> header = request.Header("authorization");
    if (!header) {
        if (std::optional<std::string> cookies = request.Header("cookie")) {
            if (std::optional<std::string> token = CookieValue(*cookies, kCookie)) {
                header = "Bearer " + *token;
            }
        }
    }
    absl::StatusOr<Caller> caller = auth_.Authenticate(header);
    if (!caller.ok()) return caller.status();
    // Every page shows jobs: a worker's token has no business here.
    if (absl::Status s = Permit(*caller, Action::kReadJobs); !s.ok()) return s;
    return caller;
}

absl::Status Dashboard::CheckPost(const HttpRequest& request) const {
    // A browser adds no Authorization header by itself: such a request is not forged.
    if (request.Header("authorization")) return absl::OkStatus();
    const std::string type = request.Header("content-type").value_or("");
    if (!absl::StartsWith(type, kJsonType)) {
        // A cross-site form can post only form types without a CORS preflight, which this
        // server never grants.
        return absl::PermissionDeniedError("expected Content-Type: application/json");
    }
    const std::optional<std::string> origin = request.Header("origin");
    const std::string expected =
        absl::StrCat(options_.tls ? "https://" : "http://", request.Header("host").value_or(""));
    if (!origin || *origin != expected) {
        return absl::PermissionDeniedError("cross-origin request refused");
    }
    return absl::OkStatus();
}

HttpAnswer Dashboard::Api(const HttpRequest& request, const std::string& route) {
    const bool post = request.method == "POST";
    if (!post && request.method != "GET") {
        HttpAnswer a = ErrorAnswer(absl::InvalidArgumentError("only GET and POST"));
        a.status = 405;
        return a;
    }
    if (post) {
        if (absl::Status s = CheckPost(request); !s.ok()) {
            Log()->warn("{} {} refused: {}", request.method, LogSafe(request.path),
                        std::string(s.message()));
            return ErrorAnswer(s);
        }
    }
    if (route == "session" && post) return SignIn(request);
    if (route == "session/end" && post) {
        HttpAnswer a = JsonAnswer(200, {{"signed_out", true}});
        a.headers.emplace_back("Set-Cookie", SessionCookie("", options_.tls, true));
        return a;
    }
    absl::StatusOr<Caller> caller = CallerOf(request);
    if (!caller.ok()) return ErrorAnswer(caller.status());
    if (route == "session" && !post) return JsonAnswer(200, CallerJson(*caller, auth_.enabled()));
    if (absl::StartsWith(route, "jobs")) return JobApi(request, *caller, route);
    if (post && absl::StartsWith(route, "workers/")) return WorkerAction(*caller, route);
    if (post) return NotFoundAnswer();
    if (route == "workers") {
        if (absl::Status s = Permit(*caller, Action::kListWorkers); !s.ok()) return ErrorAnswer(s);
        Json workers = Json::array();
        for (WorkerStatus& w : farm_.scheduler().Workers()) {
            // A submitter sees that a worker is busy, not with whose job.
            if (w.busy() && !VisibleJob(*caller, w.job_id).ok()) w.job_id = "(other)";
            workers.push_back({{"id", w.id},
                               {"name", w.name},
                               {"version", w.version},
                               {"address", w.address},
                               {"state", WorkerStateName(StateOf(w))},
                               {"tags", w.tags},
                               {"job_id", w.job_id},
                               {"task", w.task},
                               {"since_seen_ms", absl::ToInt64Milliseconds(w.since_seen)}});
        }
        return JsonAnswer(200, {{"workers", workers}});
    }
    if (route == "farm") {
        const SchedulerLoad load = farm_.scheduler().Load();
        const SchedulerMetrics& metrics = farm_.scheduler().metrics();
        const absl::Time now = absl::Now();
        return JsonAnswer(200, {{"queue_depth", load.tasks_queued},
                                {"tasks_running", load.tasks_running},
                                {"jobs_queued", load.jobs_queued},
                                {"jobs_running", load.jobs_running},
                                {"workers_live", load.workers_live},
                                {"workers_busy", load.workers_busy},
                                {"tasks_per_minute", metrics.tasks_done.LastHour(now)},
                                {"samples_per_minute", metrics.samples_done.LastHour(now)},
                                {"now_ms", absl::ToUnixMillis(now)}});
    }
    return NotFoundAnswer();
}

// POST workers/NAME/{disable,enable,drain}: as JobService's SetWorkerState, admins only; NAME a
// worker's name or id.
HttpAnswer Dashboard::WorkerAction(const Caller& caller, std::string_view route) {
    constexpr std::string_view kPrefix = "workers/";
    const size_t slash = route.rfind('/');
    if (slash <= kPrefix.size()) return NotFoundAnswer();  // no name
    const std::string name(route.substr(kPrefix.size(), slash - kPrefix.size()));
    const std::string_view what = route.substr(slash + 1);
    std::optional<WorkerControl> control;
    if (what == "disable") control = WorkerControl::kDisabled;
    if (what == "enable") control = WorkerControl::kEnabled;
    if (what == "drain") control = WorkerControl::kDrain;
    if (!control) return NotFoundAnswer();
    if (absl::Status s = Permit(caller, Action::kManageWorkers); !s.ok()) return ErrorAnswer(s);
    absl::StatusOr<std::vector<WorkerStatus>> workers = farm_.SetWorkerState(name, *control);
    if (!workers.ok()) return ErrorAnswer(workers.status());
    Log()->info("worker {} set to {} by {} from the dashboard", LogSafe(name),
                WorkerControlName(*control), caller.name);
    Json listed = Json::array();
    for (const WorkerStatus& w : *workers) {
        listed.push_back({{"id", w.id}, {"name", w.name}, {"state", WorkerStateName(StateOf(w))}});
    }
    return JsonAnswer(200, {{"workers", listed}});
}

HttpAnswer Dashboard::SignIn(const HttpRequest& request) {
    const Json body = Json::parse(request.body, nullptr, false);
    if (!body.is_object() || !body.contains("token") || !body["token"].is_string()) {
        return ErrorAnswer(absl::InvalidArgumentError("expected {\"token\": \"lf1_...\"}"));
    }
    const std::string token = body["token"].get<std::string>();
    absl::StatusOr<Caller> caller = auth_.Authenticate("Bearer " + token);
    if (caller.ok()) {
        if (absl::Status s = Permit(*caller, Action::kReadJobs); !s.ok()) caller = s;
    }
    if (!caller.ok()) {
        Log()->warn("sign-in refused: {}", LogSafe(std::string(caller.status().message())));
        return ErrorAnswer(caller.status());
    }
    Log()->info("signed in: token {}", caller->name);
    HttpAnswer a = JsonAnswer(200, CallerJson(*caller, auth_.enabled()));
    // Only a token the store knows comes back in the header: nothing else of the body does.
    a.headers.emplace_back("Set-Cookie", SessionCookie(token, options_.tls, false));
    return a;
}

absl::StatusOr<JobRecord> Dashboard::VisibleJob(const Caller& caller, const std::string& job_id) {
    const absl::Status none = absl::NotFoundError(absl::StrCat("no job ", job_id));
    if (!PlausibleJobId(job_id)) return absl::NotFoundError("no such job");
    absl::StatusOr<JobRecord> job = farm_.scheduler().Get(job_id);
    if (absl::IsNotFound(job.status()) || (job.ok() && !MaySee(caller, job->spec.owner))) {
        return none;
    }
    return job;
}

HttpAnswer Dashboard::JobApi(const HttpRequest& request, const Caller& caller,
                             const std::string& route) {
    const bool post = request.method == "POST";
    const absl::Time now = absl::Now();
    if (route == "jobs") return post ? NotFoundAnswer() : ListJobs(request, caller, now);
    // jobs/ID[/what] or jobs/ID/frames/N/what
    const std::vector<std::string> parts = absl::StrSplit(route, '/');
    if (parts.size() < 2 || parts.size() == 4 || parts.size() > 5) return NotFoundAnswer();
    const std::string& id = parts[1];
    std::string what = parts.size() >= 3 ? parts[2] : "";
    std::optional<int> frame;
    if (parts.size() == 5) {
        int n = 0;
        if (post || parts[2] != "frames" || !absl::SimpleAtoi(parts[3], &n)) {
            return NotFoundAnswer();
        }
        frame = n;
        what = parts[4];
    }
    absl::StatusOr<JobRecord> job = VisibleJob(caller, id);
    if (!job.ok()) return ErrorAnswer(job.status());
    if (frame) {
        if (absl::Status s = CheckRendersFrame(*job, *frame); !s.ok()) return ErrorAnswer(s);
        if (what != "preview.png" && what != "metadata" && what != "result.exr") {
            return NotFoundAnswer();
        }
        // A finished frame's image never changes: a browser holding it needs no new encoding.
        const FrameProgress* f = FrameOf(*job, *frame);
        if (what == "preview.png" && f && f->done &&
            NotModified(request, FramePreviewEtag(f->tasks_done, true))) {
            return {304,
                    "",
                    "",
                    {{"Cache-Control", "private, no-cache"},
                     {"ETag", FramePreviewEtag(f->tasks_done, true)}}};
        }
    }

    if (post) {
        if (what == "cancel") {
            if (absl::Status s = Permit(caller, Action::kCancelJob); !s.ok()) return ErrorAnswer(s);
            absl::StatusOr<JobRecord> cancelled = farm_.scheduler().Cancel(id);
            if (!cancelled.ok()) return ErrorAnswer(cancelled.status());
            Log()->info("job={} cancelled by {} from the dashboard", id, caller.name);
            return JsonAnswer(200, JobJson(*cancelled, now));
        }
        if (what == "priority") {
            if (absl::Status s = Permit(caller, Action::kSetPriority); !s.ok()) {
                return ErrorAnswer(s);
            }
            const Json body = Json::parse(request.body, nullptr, false);
            if (!body.is_object() || !body.contains("priority") ||
                !body["priority"].is_number_integer() ||
                body["priority"].get<int64_t>() < std::numeric_limits<int32_t>::min() ||
                body["priority"].get<int64_t>() > std::numeric_limits<int32_t>::max()) {
                return ErrorAnswer(
                    absl::InvalidArgumentError("expected {\"priority\": N}, N a 32-bit integer"));
            }
            absl::StatusOr<JobRecord> changed =
                farm_.SetPriority(id, int(body["priority"].get<int64_t>()));
            if (!changed.ok()) return ErrorAnswer(changed.status());
            Log()->info("job={} priority set to {} by {} from the dashboard", id,
                        changed->spec.priority, caller.name);
            return JsonAnswer(200, JobJson(*changed, now));
        }
        if (what == "requeue" || what == "pause" || what == "resume") {
            // As JobService's RequeueJob, PauseJob and ResumeJob: the job's owner or an admin.
            if (absl::Status s = Permit(caller, Action::kManageJobs); !s.ok())
                return ErrorAnswer(s);
            absl::StatusOr<JobRecord> changed =
                what == "requeue" ? farm_.Requeue(id)
                                  : farm_.scheduler().SetPaused(id, what == "pause");
            if (!changed.ok()) return ErrorAnswer(changed.status());
            Log()->info("job={} {} by {} from the dashboard", id,
                        what == "requeue" ? "requeued"
                        : what == "pause" ? "paused"
                                          : "resumed",
                        caller.name);
            return JsonAnswer(200, JobJson(*changed, now));
        }
        if (what == "delete") {
            if (absl::Status s = Permit(caller, Action::kDeleteJob); !s.ok()) return ErrorAnswer(s);
            if (absl::Status s = farm_.DeleteJob(id); !s.ok()) return ErrorAnswer(s);
            ForgetPreviews(id);
            Log()->info("job={} deleted by {} from the dashboard", id, caller.name);
            return JsonAnswer(200, {{"deleted", id}});
        }
        return NotFoundAnswer();
    }
    if (what.empty()) {
        absl::StatusOr<Json> body = JobWithFramesJson(request, *job, now);
        if (!body.ok()) return ErrorAnswer(body.status());
        return JsonAnswer(200, *body);
    }
    if (what == "tasks") return ListTasks(request, *job);
    if (what == "logs") {
        absl::StatusOr<int64_t> task = IntParam(request, "task", -1, 0, 1 << 30);
        absl::StatusOr<int64_t> after =
            IntParam(request, "after", 0, 0, std::numeric_limits<int64_t>::max());
        absl::StatusOr<int64_t> max = IntParam(request, "max", kDefaultLogLines, 1, kMaxLogLines);
        for (const auto* p : {&task, &after, &max}) {
            if (!p->ok()) return ErrorAnswer(p->status());
        }
        absl::StatusOr<TaskLogPage> page = farm_.TaskLogs(
            id, *task < 0 ? std::nullopt : std::optional<int>(int(*task)), *after, int(*max));
        if (!page.ok()) return ErrorAnswer(page.status());
        Json lines = Json::array();
        for (const TaskLogLine& l : page->lines) {
            lines.push_back({{"seq", l.seq},
                             {"task", l.task},
                             {"attempt", l.attempt},
                             {"worker", l.worker},
                             {"time_ms", absl::ToUnixMillis(l.time)},
                             {"level", l.level},
                             {"text", l.text}});
        }
        return JsonAnswer(
            200, {{"lines", lines}, {"next_seq", page->next_seq}, {"ended", page->job_ended}});
    }
    if (what == "result.exr") {
        absl::StatusOr<std::string> path = farm_.ResultFile(id, false, frame);
        if (!path.ok()) return ErrorAnswer(path.status());
        HttpAnswer a{200, "image/x-exr", "", {{"Cache-Control", "private, no-cache"}}, *path};
        a.headers.emplace_back("Content-Disposition", AttachmentHeader(id, frame, "exr"));
        Log()->info("job={} result downloaded by {} from the dashboard", id, caller.name);
        return a;
    }
    if (what == "preview.png" || what == "metadata") {
        HttpAnswer a;
        if (what == "preview.png" && (request.Query("exposure") || request.Query("channel"))) {
            a = GradedPreviewAnswer(request, *job, frame);
        } else {
            absl::StatusOr<std::shared_ptr<const Preview>> preview = PreviewOf(*job, frame);
            if (!preview.ok()) return ErrorAnswer(preview.status());
            a = PreviewAnswer(request, **preview, what);
        }
        if (a.status == 200 && what == "preview.png" && request.Query("download")) {
            a.headers.emplace_back("Content-Disposition", AttachmentHeader(id, frame, "png"));
        }
        return a;
    }
    return NotFoundAnswer();
}

HttpAnswer Dashboard::ListJobs(const HttpRequest& request, const Caller& caller, absl::Time now) {
    absl::StatusOr<int64_t> limit = IntParam(request, "limit", kDefaultJobs, 1, kMaxJobs);
    absl::StatusOr<int64_t> before =
        IntParam(request, "before", 0, 0, std::numeric_limits<int64_t>::max());
    absl::StatusOr<std::string> state_name = FilterParam(request, "state");
    absl::StatusOr<std::string> owner = FilterParam(request, "owner");
    absl::StatusOr<std::string> name = FilterParam(request, "name");
    if (!limit.ok()) return ErrorAnswer(limit.status());
    if (!before.ok()) return ErrorAnswer(before.status());
    for (const auto* p : {&state_name, &owner, &name}) {
        if (!p->ok()) return ErrorAnswer(p->status());
    }
    std::optional<JobState> state;
    if (!state_name->empty()) {
        absl::StatusOr<JobState> s = JobStateFromName(*state_name);
        if (!s.ok()) {
            return ErrorAnswer(absl::InvalidArgumentError(
                absl::StrCat("state: ", LogSafe(std::string(s.status().message())))));
        }
        state = *s;
    }
    JobQuery query{.before_seq = uint64_t(*before), .limit = kJobsReadAtOnce};
    if (!owner->empty()) query.owner = *owner;
    Json list = Json::array();
    Json next = nullptr;  // `before` of the next page; null when no job is left
    // A submitter lists its own jobs: another owner's are none.
    const bool others = caller.role != Role::kAdmin && query.owner && *query.owner != caller.name;
    if (caller.role != Role::kAdmin) query.owner = caller.name;
    const std::string needle = absl::AsciiStrToLower(*name);
    for (size_t scanned = 0; !others;) {
        absl::StatusOr<std::vector<JobRecord>> jobs = farm_.scheduler().List(query);
        if (!jobs.ok()) return ErrorAnswer(jobs.status());
        for (const JobRecord& job : *jobs) {
            ++scanned;
            query.before_seq = job.seq;
            if (state && job.state != *state) continue;
            if (!needle.empty() &&
                !absl::StrContains(absl::AsciiStrToLower(job.spec.name), needle) &&
                !absl::StrContains(job.id, needle)) {
                continue;
            }
            list.push_back(JobJson(job, now));
            if (list.size() == size_t(*limit)) break;
        }
        // A full page, or as many jobs read as one request may: the next page goes on from here.
        if (list.size() == size_t(*limit) ||
            (jobs->size() == kJobsReadAtOnce && scanned >= kMaxJobsScanned)) {
            next = query.before_seq;
            break;
        }
        if (jobs->size() < kJobsReadAtOnce) break;
    }
    return JsonAnswer(200,
                      {{"jobs", list}, {"next_before", next}, {"now_ms", absl::ToUnixMillis(now)}});
}

HttpAnswer Dashboard::ListTasks(const HttpRequest& request, const JobRecord& job) {
    std::optional<int> only;  // ?frame=N: a shot's frame's tasks
    if (request.Query("frame")) {
        absl::StatusOr<int64_t> n =
            IntParam(request, "frame", 0, -kMaxFrameNumber, kMaxFrameNumber);
        if (!n.ok()) return ErrorAnswer(n.status());
        if (absl::Status s = CheckRendersFrame(job, int(*n)); !s.ok()) return ErrorAnswer(s);
        only = int(*n);
    }
    absl::StatusOr<std::optional<TaskStatus::State>> state = TaskStateParam(request);
    absl::StatusOr<int64_t> offset = IntParam(request, "offset", 0, 0, 1 << 30);
    absl::StatusOr<int64_t> limit = IntParam(request, "limit", kDefaultTasks, 1, kMaxTasks);
    if (!state.ok()) return ErrorAnswer(state.status());
    if (!offset.ok()) return ErrorAnswer(offset.status());
    if (!limit.ok()) return ErrorAnswer(limit.status());
    absl::StatusOr<std::vector<TaskStatus>> tasks = farm_.Tasks(job.id);
    if (!tasks.ok()) return ErrorAnswer(tasks.status());
    Json list = Json::array();
    Json counts = Json::object();  // the job's (or the frame's) tasks by state, unfiltered
    int64_t matching = 0;
    for (const TaskStatus& t : *tasks) {
        if (only && std::find(t.frames.begin(), t.frames.end(), *only) == t.frames.end()) {
            continue;
        }
        const std::string name = TaskStatusName(t.state);
        counts[name] = counts.value(name, 0) + 1;
        if (*state && t.state != **state) continue;
        if (matching >= *offset && matching < *offset + *limit) list.push_back(TaskJson(t));
        ++matching;
    }
    return JsonAnswer(
        200, {{"tasks", list}, {"total", matching}, {"offset", *offset}, {"counts", counts}});
}

HttpAnswer Dashboard::GradedPreviewAnswer(const HttpRequest& request, const JobRecord& job,
                                          std::optional<int> frame) {
    absl::StatusOr<double> exposure =
        DoubleParam(request, "exposure", 0, -kMaxExposure, kMaxExposure);
    if (!exposure.ok()) return ErrorAnswer(exposure.status());
    absl::StatusOr<std::string> channel = FilterParam(request, "channel");
    if (!channel.ok()) return ErrorAnswer(channel.status());
    absl::StatusOr<std::shared_ptr<const Preview>> preview = PreviewOf(job, frame);
    if (!preview.ok()) return ErrorAnswer(preview.status());
    const std::string etag =
        absl::StrCat("\"", absl::StripSuffix(absl::StripPrefix((*preview)->etag, "\""), "\""), "/",
                     *exposure, "/", channel->empty() ? "beauty" : *channel, "\"");
    std::vector<std::pair<std::string, std::string>> headers = {
        {"Cache-Control", "private, no-cache"}, {"ETag", etag}};
    if (NotModified(request, etag)) return {304, "", "", std::move(headers)};
    {
        std::unique_lock<std::mutex> lock(graded_mutex_);
        if (!graded_turn_.wait_for(lock, std::chrono::seconds(30),
                                   [&] { return graded_running_ < kGradedAtOnce; })) {
            return ErrorAnswer(absl::UnavailableError("graded previews are busy; try again"));
        }
        ++graded_running_;
    }
    absl::Cleanup turn_done = [&] {
        std::lock_guard<std::mutex> lock(graded_mutex_);
        --graded_running_;
        graded_turn_.notify_one();
    };
    absl::StatusOr<std::shared_ptr<const Image>> image = GradedSource(job, frame, **preview);
    if (!image.ok()) return ErrorAnswer(image.status());
    absl::StatusOr<ChannelView> view = ViewChannel(**image, channel->empty() ? "beauty" : *channel);
    if (!view.ok()) return ErrorAnswer(view.status());
    absl::StatusOr<std::string> png =
        EncodePng(view->rgb, {.exposure = *exposure, .tone = view->tone});
    if (!png.ok()) return ErrorAnswer(png.status());
    return {200, "image/png", std::move(*png), std::move(headers)};
}

absl::StatusOr<std::shared_ptr<const Image>> Dashboard::GradedSource(const JobRecord& job,
                                                                     std::optional<int> frame,
                                                                     const Preview& preview) {
    const std::string key =
        absl::StrCat(frame ? absl::StrCat(job.id, "/", *frame) : job.id, " ", preview.etag);
    {
        std::lock_guard<std::mutex> lock(previews_mutex_);
        if (graded_.key == key) return graded_.image;
    }
    absl::StatusOr<ExrFile> exr = ReadResult(job, frame);
    if (!exr.ok()) return exr.status();
    auto image = std::make_shared<const Image>(std::move(exr->image));
    std::lock_guard<std::mutex> lock(previews_mutex_);
    graded_ = {key, image};
    return image;
}

absl::StatusOr<ExrFile> Dashboard::ReadResult(const JobRecord& job, std::optional<int> frame) {
    absl::StatusOr<std::string> path = farm_.ResultFile(job.id, true, frame);
    if (!path.ok()) return path.status();
    absl::StatusOr<ExrFile> exr = ReadExr(*path);
    if (!exr.ok()) {
        Log()->error("job={}: preview: {}", job.id, std::string(exr.status().message()));
        return absl::UnavailableError("the preview cannot be read on the server");
    }
    return exr;
}

void Dashboard::ForgetPreviews(const std::string& job_id) {
    std::lock_guard<std::mutex> lock(previews_mutex_);
    if (absl::StartsWith(graded_.key, job_id + " ") ||
        absl::StartsWith(graded_.key, job_id + "/")) {
        graded_ = {};
    }
    std::erase_if(previews_, [&](const auto& entry) {
        return entry.first == job_id || absl::StartsWith(entry.first, job_id + "/");
    });
}

absl::StatusOr<Json> Dashboard::JobWithFramesJson(const HttpRequest& request, const JobRecord& job,
                                                  absl::Time now) {
    Json body = JobJson(job, now);
    // Dependencies (issue 30): the jobs it runs after, each in its state now.
    if (!job.spec.after.empty()) {
        Json after = Json::array();
        for (const std::string& dep : job.spec.after) {
            const absl::StatusOr<JobRecord> d = farm_.scheduler().Get(dep);
            after.push_back({{"id", dep}, {"state", d.ok() ? JobStateName(d->state) : "deleted"}});
        }
        body["depends_on"] = std::move(after);
    }
    if (!job.spec.shot.frames) return body;
    const FrameRange& range = *job.spec.shot.frames;
    // The page of the current frame unless another is asked for.
    const int current = range.IndexOf(body["shot"]["current"].get<int>());
    absl::StatusOr<int64_t> from = IntParam(
        request, "frames_from", current / kFramesListed * kFramesListed, 0, range.count() - 1);
    if (!from.ok()) return from.status();
    std::set<int> running;
    if (job.tasks_running > 0) {
        // The scheduler's own view of the tasks: no log line counts read for it.
        for (const TaskStatus& t :
             farm_.scheduler().Tasks(job.id).value_or(std::vector<TaskStatus>{})) {
            if (t.state == TaskStatus::State::kRunning) {
                running.insert(t.frames.begin(), t.frames.end());
            }
        }
    }
    body["shot"]["frames_from"] = *from;
    body["shot"]["frames_per_page"] = kFramesListed;
    body["frames"] = FramesJson(job, int(*from), running);
    return body;
}

HttpAnswer Dashboard::PreviewAnswer(const HttpRequest& request, const Preview& preview,
                                    const std::string& what) {
    std::vector<std::pair<std::string, std::string>> headers = {
        {"Cache-Control", "private, no-cache"}, {"ETag", preview.etag}};
    if (what == "metadata") {
        Json attributes = Json::object();
        for (const auto& [name, value] : preview.attributes) {
            attributes[name] = AttributeJson(value);
        }
        return JsonAnswer(200, {{"attributes", attributes}, {"channels", preview.channels}});
    }
    if (NotModified(request, preview.etag)) return {304, "", "", std::move(headers)};
    return {200, "image/png", preview.png, std::move(headers)};
}

absl::StatusOr<std::shared_ptr<const Dashboard::Preview>> Dashboard::PreviewOf(
    const JobRecord& job, std::optional<int> frame) {
    // What the image shows: the job's merged tasks, or the frame's.
    int tasks_done = job.tasks_done;
    bool frame_done = false;
    if (frame) {
        if (const FrameProgress* f = FrameOf(job, *frame)) {
            tasks_done = f->tasks_done;
            frame_done = f->done;
        }
    }
    const std::string key = frame ? absl::StrCat(job.id, "/", *frame) : job.id;
    {
        std::lock_guard<std::mutex> lock(previews_mutex_);
        auto it = previews_.find(key);
        // A job that failed or was cancelled keeps the last preview shown of it (of a frame,
        // unless the frame was finished since).
        if (it != previews_.end() &&
            ((it->second->tasks_done == tasks_done && it->second->frame_done == frame_done &&
              (frame || it->second->state == job.state)) ||
             (!IsFinal(job.state) && absl::Now() - it->second->made < options_.preview_min_age) ||
             (IsFinal(job.state) && job.state != JobState::kSucceeded &&
              it->second->frame_done == frame_done))) {
            it->second->used = ++preview_clock_;
            return it->second;
        }
    }
    absl::StatusOr<ExrFile> exr = ReadResult(job, frame);
    if (!exr.ok()) return exr.status();
    // Filmic: highlights roll off instead of clipping, as a look at a render in progress wants.
    absl::StatusOr<std::string> png = EncodePng(exr->image, {.tone = ToneCurve::kFilmic});
    if (!png.ok()) return png.status();
    auto preview = std::make_shared<Preview>(
        Preview{.tasks_done = tasks_done,
                .state = job.state,
                .frame_done = frame_done,
                .etag = frame ? FramePreviewEtag(tasks_done, frame_done)
                              : absl::StrCat("\"", tasks_done, "-", int(job.state), "\""),
                .png = std::move(*png),
                .channels = PreviewChannels(exr->image),
                .attributes = std::move(exr->attributes),
                .made = absl::Now()});
    std::lock_guard<std::mutex> lock(previews_mutex_);
    preview->used = ++preview_clock_;
    previews_[key] = preview;
    if (previews_.size() > kMaxPreviews) {
        auto oldest = std::min_element(previews_.begin(), previews_.end(), [](auto& a, auto& b) {
            return a.second->used < b.second->used;
        });
        previews_.erase(oldest);
    }
    return preview;
}

}  // namespace lf
