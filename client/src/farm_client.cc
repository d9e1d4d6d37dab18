#include "lf/client/farm_client.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/proto/channel.h"
#include "lf/proto/connection_status.h"
#include "lf/wire/conversions.h"

namespace lf {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

namespace {

constexpr size_t kChunkBytes = 1 << 20;

// Uploads whose bytes add up to this show a progress bar (on a terminal).
constexpr uint64_t kProgressBarBytes = uint64_t(16) << 20;

// Waits between attempts to reach a server that is down: 0.25 s, doubling up to 5 s, until the
// budget is spent, saying on stderr what it waits for.
class Backoff {
  public:
    explicit Backoff(const FarmFlags& flags) : budget_(absl::Seconds(flags.retry_seconds)) {}

    // False when the budget is spent: give up with `why`.
    bool Wait(const std::string& what, const absl::Status& why) {
        if (waited_ + delay_ > budget_) return false;
        std::fprintf(stderr, "lightfarm: %s: %s; retrying in %.2g s\n", what.c_str(),
                     std::string(why.message()).c_str(), absl::ToDoubleSeconds(delay_));
        absl::SleepFor(delay_);
        waited_ += delay_;
        delay_ = std::min(2 * delay_, kMaxDelay);
        return true;
    }
    // The server answered: a later outage gets the whole budget again.
    void Reset() {
        waited_ = absl::ZeroDuration();
        delay_ = kFirstDelay;
    }

  private:
    static constexpr absl::Duration kFirstDelay = absl::Milliseconds(250);
    static constexpr absl::Duration kMaxDelay = absl::Seconds(5);
    absl::Duration budget_;
    absl::Duration waited_ = absl::ZeroDuration();
    absl::Duration delay_ = kFirstDelay;
};

// Aborted: another client was uploading one of the blobs; the retry resumes from its bytes, or
// finds the blob stored.
bool SubmitMayRetry(const absl::Status& s) { return absl::IsUnavailable(s) || absl::IsAborted(s); }

}  // namespace

FarmClient::FarmClient(const FarmFlags& flags) : flags_(flags) { Connect(); }

// A new channel: after an outage, retries take a new one, as a channel that failed to connect
// fails calls fast for a while after the server is back.
void FarmClient::Connect() {
    absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = OpenChannel(flags_.channel);
    if (!channel.ok()) {
        std::fprintf(stderr, "lightfarm: error: %s\n",
                     std::string(channel.status().message()).c_str());
        std::exit(2);
    }
    stub_ = pb::JobService::NewStub(*channel);
}

// The server's own words, with where it was asked when it could not be reached.
absl::Status FarmClient::CallStatus(const grpc::Status& s) const {
    return ConnectionStatus(s, flags_.channel);
}

absl::Status FarmClient::Retrying(const std::string& what,
                                  const std::function<absl::Status()>& attempt,
                                  bool (*transient)(const absl::Status&)) {
    Backoff backoff(flags_);
    while (true) {
        const absl::Status s = attempt();
        if (!transient(s) || !backoff.Wait(what, s)) return s;
        Connect();
    }
}

// Sends what the server lacks of one blob: from where its bytes end (BlobUploadOffset), so an
// upload that broke resumes instead of starting over. `sent` counts the bytes the server holds
// of the blobs uploaded so far, of `total`, for `bar` (null: no bar).
absl::Status FarmClient::Upload(const BlobRef& file, const std::string& content, uint64_t& sent,
                                uint64_t total, ProgressBar* bar) {
    auto failed = [&](const absl::Status& s) {
        return absl::Status(s.code(), absl::StrCat(file.path, ": upload: ", s.message()));
    };
    pb::BlobUploadOffsetRequest where;
    where.set_hash(file.hash);
    where.set_size(file.size);
    pb::BlobUploadOffsetResponse held;
    const grpc::Status asked =
        stub_->BlobUploadOffset(ContextWithDeadline(absl::Seconds(10)).get(), where, &held);
    // A server of an earlier version, without the call, takes whole uploads only.
    if (!asked.ok() && asked.error_code() != grpc::StatusCode::UNIMPLEMENTED) {
        return failed(CallStatus(asked));
    }
    const size_t offset = std::min<uint64_t>(held.offset(), content.size());
    if (offset > 0 && offset < content.size()) {
        std::fprintf(stderr, "lightfarm: %s: the server holds %zu of %zu bytes; sending the rest\n",
                     file.path.c_str(), offset, content.size());
    }
    sent += offset;
    if (offset == content.size()) return absl::OkStatus();

    const auto context = ContextWithDeadline(absl::Minutes(10));
    pb::UploadBlobResponse response;
    std::unique_ptr<grpc::ClientWriter<pb::UploadBlobRequest>> writer =
        stub_->UploadBlob(context.get(), &response);
    pb::UploadBlobRequest chunk;
    chunk.set_hash(file.hash);
    chunk.set_size(file.size);
    chunk.set_offset(offset);
    size_t at = offset;
    do {
        const size_t n = std::min(kChunkBytes, content.size() - at);
        chunk.set_data(content.data() + at, n);
        if (!writer->Write(chunk)) break;
        at += n;
        sent += n;
        if (bar) bar->Update(sent, total);
        chunk.clear_hash();
        chunk.clear_size();
        chunk.clear_offset();
    } while (at < content.size());
    writer->WritesDone();
    if (absl::Status s = CallStatus(writer->Finish()); !s.ok()) return failed(s);
    return absl::OkStatus();
}

// Uploads the blobs the server lacks and submits the job: one attempt.
absl::Status FarmClient::SubmitOnce(const std::vector<BlobRef>& files,
                                    const std::map<std::string, std::string>& blobs,
                                    const pb::SubmitJobRequest& request, std::string* id) {
    pb::MissingBlobsRequest missing_req;
    for (const auto& [hash, content] : blobs) missing_req.add_hashes(hash);
    pb::MissingBlobsResponse missing;
    if (absl::Status s = Call(&pb::JobService::Stub::MissingBlobs, missing_req, &missing);
        !s.ok()) {
        return s;
    }
    std::vector<const BlobRef*> uploads;
    uint64_t total = 0, sent = 0;
    for (const std::string& hash : missing.hashes()) {
        for (const BlobRef& f : files) {
            if (f.hash != hash) continue;
            uploads.push_back(&f);
            total += f.size;
            break;
        }
    }
    std::optional<ProgressBar> bar;
    if (total >= kProgressBarBytes) bar.emplace("upload");
    for (const BlobRef* f : uploads) {
        const absl::Status s = Upload(*f, blobs.at(f->hash), sent, total, bar ? &*bar : nullptr);
        if (!s.ok()) {
            if (bar) bar->Finish();  // the bar's line ends before the error's
            return s;
        }
    }
    if (bar) bar->Finish();

    pb::SubmitJobResponse response;
    // The server loads the scene to check it, which takes a while for large meshes.
    if (absl::Status s = CallStatus(
            stub_->SubmitJob(ContextWithDeadline(absl::Minutes(2)).get(), request, &response));
        !s.ok()) {
        return s;
    }
    *id = response.job_id();
    return absl::OkStatus();
}

absl::StatusOr<std::string> FarmClient::Submit(const JobSpec& spec,
                                               const std::map<std::string, std::string>& blobs) {
    std::vector<BlobRef> files = {spec.scene};
    files.insert(files.end(), spec.files.begin(), spec.files.end());
    pb::SubmitJobRequest request;
    ToProto(spec, &request);
    std::string id;
    if (absl::Status s = Retrying(
            "submit", [&] { return SubmitOnce(files, blobs, request, &id); }, &SubmitMayRetry);
        !s.ok()) {
        return s;
    }
    return id;
}

// Each call has a deadline; the watch goes on across them.
absl::StatusOr<pb::Job> FarmClient::Watch(const std::string& id, ProgressBar& bar) {
    pb::WatchJobRequest req;
    req.set_job_id(id);
    pb::Job job;
    Backoff backoff(flags_);
    while (true) {
        const auto context = ContextWithDeadline(absl::Minutes(1));
        std::unique_ptr<grpc::ClientReader<pb::Job>> reader = stub_->WatchJob(context.get(), req);
        while (reader->Read(&job)) {
            backoff.Reset();
            bar.Update(size_t(job.tasks_done()), size_t(std::max(1, job.tasks_total())));
            if (IsFinal(FromProto(job.state()))) return job;
        }
        const grpc::Status s = reader->Finish();
        if (s.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) continue;
        if (const absl::Status status = CallStatus(s);
            absl::IsUnavailable(status) && backoff.Wait("watch " + id, status)) {
            Connect();
            continue;
        }
        if (!s.ok()) return CallStatus(s);
        if (IsFinal(FromProto(job.state()))) return job;
    }
}

absl::Status FarmClient::FetchResult(const std::string& id, const std::string& path, bool preview,
                                     std::optional<int> frame) {
    pb::FetchResultRequest req;
    req.set_job_id(id);
    req.set_preview(preview);
    if (frame) req.set_frame(*frame);
    const auto context = ContextWithDeadline(absl::Minutes(30));
    std::unique_ptr<grpc::ClientReader<pb::Chunk>> reader = stub_->FetchResult(context.get(), req);
    // Written beside the target and renamed, so a failed fetch leaves no half file.
    const std::string temp = path + ".part";
    std::ofstream file(temp, std::ios::binary);
    if (!file) return absl::PermissionDeniedError(path + ": cannot write here");
    pb::Chunk chunk;
    while (reader->Read(&chunk)) {
        file.write(chunk.data().data(), std::streamsize(chunk.data().size()));
    }
    file.close();
    std::error_code ec;
    if (absl::Status s = CallStatus(reader->Finish()); !s.ok() || !file) {
        fs::remove(temp, ec);
        return s.ok() ? absl::InternalError(path + ": write failed") : s;
    }
    fs::rename(temp, path, ec);
    if (ec) return absl::InternalError(path + ": " + ec.message());
    return absl::OkStatus();
}

}  // namespace lf
