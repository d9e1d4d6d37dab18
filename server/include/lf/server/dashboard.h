// The web dashboard of lightfarm-server's --http listener: its pages (server/web/, embedded at
// build time) and the JSON API they poll, a thin adapter over Farm as the gRPC services are. A
// caller is who its token says (an `lf_token` cookie set by signing in, or Authorization:
// Bearer) and sees what the gRPC API would show that token: a submitter its own jobs (another's
// answers 404 exactly as a job that does not exist), workers without other owners' job ids;
// worker tokens may not use it. With authentication off (no tokens, gRPC on loopback) everyone
// is an anonymous admin, as on the gRPC port, but only from this machine and through a loopback
// Host (against DNS rebinding). Plain logic over HttpRequest and HttpAnswer, tested without HTTP.
//
//   GET  /, /web/NAME                 the pages
//   GET  /api/session                 who is signed in (401 when no one is and tokens are on)
//   POST /api/session {"token": T}    signs in: an HttpOnly, SameSite=Strict cookie
//   POST /api/session/end             signs out
//   GET  /api/jobs?limit=N&before=SEQ&state=S&owner=O&name=TEXT
//                                     newest first, filtered (state exactly, owner exactly, TEXT
//                                     a case-blind substring of the name or id); next_before: the
//                                     `before` of the next page (null at the end)
//   GET  /api/jobs/ID?frames_from=I   one job, with its ETA; a shot's with its frames: at most
//                                     kFramesListed of them from position I of its range
//                                     (default: the page of its current frame)
//   GET  /api/jobs/ID/tasks?frame=N&state=S&offset=I&limit=N
//                                     its tasks (a shot's frame N's only) in state S, a page of
//                                     them, their total and counts by state
//   GET  /api/jobs/ID/logs?task=N&after=SEQ&max=N
//   GET  /api/jobs/ID/preview.png     the image merged so far, 8-bit sRGB; ?exposure=EV (-8..8)
//                                     and ?channel=beauty|A|B|albedo|normal|depth tone-map it from
//                                     the linear EXR; ?download=1 as an attachment
//   GET  /api/jobs/ID/metadata        the EXR header attributes of that image, its channels
//   GET  /api/jobs/ID/result.exr      a succeeded job's EXR as an attachment, streamed
//   GET  /api/jobs/ID/frames/N/preview.png, .../metadata, .../result.exr   a shot's frame N's
//   POST /api/jobs/ID/cancel
//   POST /api/jobs/ID/delete          an ended job (the roles of the gRPC DeleteJob)
//   POST /api/jobs/ID/priority {"priority": N}
//   GET  /api/workers
//   GET  /api/farm                    queue depth, workers, throughput per minute of the last hour
//
// POSTs must come as application/json from the page's own origin (CSRF), unless they carry
// Authorization: Bearer, which a browser never adds by itself.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/image_io.h"
#include "lf/server/auth.h"
#include "lf/server/farm.h"
#include "lf/server/http_exchange.h"

namespace lf {

struct DashboardOptions {
    bool tls = false;  // served over HTTPS: the cookie is Secure, the page's origin https://
    // A running job's preview is made again (its EXR written and read, its PNG encoded) at most
    // this often, however many tabs watch it and however fast its tasks merge.
    absl::Duration preview_min_age = absl::Seconds(2);
};

class Dashboard {
  public:
    Dashboard(Farm& farm, Authenticator& auth, DashboardOptions options);

    // Answers any request for / , /web/... or /api/...; 404 for other paths.
    HttpAnswer Serve(const HttpRequest& request);

    // The name of the session cookie.
    static constexpr char kCookie[] = "lf_token";
    // Previews kept encoded, the most recently asked for.
    static constexpr size_t kMaxPreviews = 16;
    // Graded previews (exposure, channel) made at once: each costs a full-size image's memory.
    static constexpr int kGradedAtOnce = 2;
    // Frames of a shot one job answer lists: the page's strip pages through longer shots.
    static constexpr int kFramesListed = 100;

  private:
    struct Preview {
        int tasks_done = 0;  // the job's, or the frame's
        JobState state = JobState::kQueued;
        bool frame_done = false;
        std::string etag;  // its version
        std::string png;
        std::vector<std::string> channels;  // the views the image has (PreviewChannels)
        ExrAttributes attributes;
        absl::Time made;
        uint64_t used = 0;  // the cache's clock when last asked for
    };

    HttpAnswer Api(const HttpRequest& request, const std::string& route);
    HttpAnswer SignIn(const HttpRequest& request);
    HttpAnswer WorkerAction(const Caller& caller, std::string_view route);
    HttpAnswer JobApi(const HttpRequest& request, const Caller& caller, const std::string& route);
    absl::StatusOr<Caller> CallerOf(const HttpRequest& request);
    // CSRF: a POST's content type and origin.
    absl::Status CheckPost(const HttpRequest& request) const;
    // The job when `caller` may see it; NotFound alike for another's job and for none.
    absl::StatusOr<JobRecord> VisibleJob(const Caller& caller, const std::string& job_id);
    // The job's image as merged so far (or its result), encoded again only when a task was
    // merged since, and not more often than preview_min_age while the job runs; a shot's
    // `frame`'s likewise (NotFound naming the frame and the job for one it does not render).
    absl::StatusOr<std::shared_ptr<const Preview>> PreviewOf(const JobRecord& job,
                                                             std::optional<int> frame);
    // GET /api/jobs: newest first, filtered by state, owner and a name's (or id's) substring.
    HttpAnswer ListJobs(const HttpRequest& request, const Caller& caller, absl::Time now);
    // GET /api/jobs/ID/tasks: a page of the tasks in a state (a shot's frame's), with counts.
    HttpAnswer ListTasks(const HttpRequest& request, const JobRecord& job);
    // preview.png?exposure=EV&channel=NAME: made from the linear image of the preview's version
    // (PreviewOf), which is kept for the last image graded; its ETag names the version, the
    // exposure and the channel. At most kGradedAtOnce are made at once; others wait for a turn.
    HttpAnswer GradedPreviewAnswer(const HttpRequest& request, const JobRecord& job,
                                   std::optional<int> frame);
    // The linear image of `preview`'s version of the job's (frame's) result, read once a version.
    absl::StatusOr<std::shared_ptr<const Image>> GradedSource(const JobRecord& job,
                                                              std::optional<int> frame,
                                                              const Preview& preview);
    // The job's (or frame's) image as merged so far, read from its EXR.
    absl::StatusOr<ExrFile> ReadResult(const JobRecord& job, std::optional<int> frame);
    // Drops a deleted job's cached previews.
    void ForgetPreviews(const std::string& job_id);
    // One job's JSON; a shot's with the page of its frames `frames_from` asks for.
    absl::StatusOr<nlohmann::json> JobWithFramesJson(const HttpRequest& request,
                                                     const JobRecord& job, absl::Time now);
    // preview.png and metadata of `preview`, whose ETag names its version.
    HttpAnswer PreviewAnswer(const HttpRequest& request, const Preview& preview,
                             const std::string& what);

    Farm& farm_;
    Authenticator& auth_;
    const DashboardOptions options_;
    std::mutex previews_mutex_;
    std::map<std::string, std::shared_ptr<Preview>> previews_;  // by job id (and frame)
    uint64_t preview_clock_ = 0;
    // The image last graded: a user dragging the exposure slider asks for one image many times.
    struct GradedImage {
        std::string key;  // job id (and frame) and the preview's ETag
        std::shared_ptr<const Image> image;
    };
    GradedImage graded_;  // under previews_mutex_
    // Graded previews being made now (each holds an image and its encoding), under graded_mutex_.
    std::mutex graded_mutex_;
    std::condition_variable graded_turn_;
    int graded_running_ = 0;
};

}  // namespace lf
