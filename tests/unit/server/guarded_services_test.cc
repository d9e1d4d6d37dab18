// The services behind TLS and tokens, over real gRPC channels made as `lightfarm` and
// `lightfarm-worker` make them (lf::OpenChannel): each role can do what it may and nothing
// else, and nothing of another submitter's job leaks through any call.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>

#include "lf/core/file_util.h"
#include "lf/job/digest.h"
#include "lf/proto/channel.h"
#include "lf/server/grpc_service.h"
#include "lf/server/server_credentials.h"
#include "lf/version.h"
#include "lightfarm/v1/job_service.grpc.pb.h"
#include "lightfarm/v1/worker_service.grpc.pb.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

// A CA, the server's certificate for 127.0.0.1, a worker's certificate from the CA and one from
// another CA, made by the openssl command (deploy/install-deps.sh installs it).
void MakeCertificates(const fs::path& dir) {
    const std::string d = dir.string();
    const std::string script =
        "set -e; cd '" + d +
        "'; q='-days 2 -sha256'; "
        "for ca in ca other; do openssl req -x509 -newkey rsa:2048 -nodes -keyout $ca.key "
        "-out $ca.crt $q -subj /CN=$ca; done; "
        "openssl req -newkey rsa:2048 -nodes -keyout server.key -out server.csr -subj "
        "/CN=server; printf 'subjectAltName=IP:127.0.0.1\\n' > san; "
        "openssl x509 -req -in server.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out "
        "server.crt $q -extfile san; "
        "for w in worker:ca rogue:other; do n=${w%:*}; c=${w#*:}; "
        "openssl req -newkey rsa:2048 -nodes -keyout $n.key -out $n.csr -subj /CN=$n; "
        "openssl x509 -req -in $n.csr -CA $c.crt -CAkey $c.key -CAcreateserial -out $n.crt $q; "
        "done";
    ASSERT_EQ(std::system(("(" + script + ") >/dev/null 2>&1").c_str()), 0)
        << "openssl could not make the test certificates";
}

class GuardedServices : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_guarded");
        MakeCertificates(dir_);
        FarmOptions options;
        options.data_dir = (dir_ / "data").string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        auto tokens = TokenStore::Open(options.data_dir);
        ASSERT_TRUE(tokens.ok());
        for (auto [name, role] :
             {std::pair{"alice", Role::kSubmitter}, std::pair{"bob", Role::kSubmitter},
              std::pair{"node", Role::kWorker}, std::pair{"root", Role::kAdmin}}) {
            absl::StatusOr<std::string> token = (*tokens)->Create(name, role);
            ASSERT_TRUE(token.ok());
            std::ofstream(dir_ / (std::string(name) + ".token")) << *token << "\n";
        }
        auth_ = std::make_unique<Authenticator>(std::move(*tokens), true);
        jobs_ = std::make_unique<JobServiceImpl>(*farm_, CallGuard{*auth_, true}, service_options_);
        workers_ = std::make_unique<WorkerServiceImpl>(*farm_, CallGuard{*auth_, true});
        auto credentials = MakeServerCredentials({.cert = (dir_ / "server.crt").string(),
                                                  .key = (dir_ / "server.key").string(),
                                                  .client_ca = (dir_ / "ca.crt").string()});
        ASSERT_TRUE(credentials.ok()) << credentials.status();
        grpc::ServerBuilder builder;
        int port = 0;
        builder.AddListeningPort("127.0.0.1:0", *credentials, &port);
        builder.RegisterService(jobs_.get());
        builder.RegisterService(workers_.get());
        server_ = builder.BuildAndStart();
        ASSERT_TRUE(server_ && port > 0);
        address_ = "127.0.0.1:" + std::to_string(port);

        const absl::StatusOr<std::string> scene =
            ReadFile((fs::path(LF_TEST_SCENES) / "cornell_box.json").string());
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene_ = {"scene.json", Sha256Hex(*scene), scene->size()};
        auto upload = farm_->blobs().StartUpload(scene_.hash, scene_.size);
        ASSERT_TRUE(upload.ok());
        ASSERT_TRUE((*upload)->Append(*scene).ok() && (*upload)->Finish().ok());
    }
    void TearDown() override {
        farm_->scheduler().Shutdown();
        server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
        fs::remove_all(dir_);
    }

    // A channel as `lightfarm --tls-ca ca.crt --token-file WHO.token` makes it; "" for no token.
    std::shared_ptr<grpc::Channel> Channel(const std::string& who, const std::string& cert = "") {
        ChannelOptions options{.address = address_, .tls_ca = (dir_ / "ca.crt").string()};
        if (!who.empty()) options.token_file = (dir_ / (who + ".token")).string();
        if (!cert.empty()) {
            options.tls_cert = (dir_ / (cert + ".crt")).string();
            options.tls_key = (dir_ / (cert + ".key")).string();
        }
        auto channel = OpenChannel(options);
        EXPECT_TRUE(channel.ok()) << channel.status();
        return *channel;
    }
    std::unique_ptr<pb::JobService::Stub> Jobs(const std::string& who) {
        return pb::JobService::NewStub(Channel(who));
    }
    static std::unique_ptr<grpc::ClientContext> Context() {
        auto context = std::make_unique<grpc::ClientContext>();
        context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
        return context;
    }

    grpc::Status Submit(pb::JobService::Stub& stub, std::string* id,
                        const std::string& request_id = "") {
        pb::SubmitJobRequest request;
        request.set_request_id(request_id);
        request.mutable_scene()->set_path(scene_.path);
        request.mutable_scene()->set_hash(scene_.hash);
        request.mutable_scene()->set_size(scene_.size);
        request.mutable_params()->set_spp(1);
        request.mutable_params()->set_width(8);
        request.mutable_params()->set_height(8);
        request.mutable_params()->set_tile(8);
        request.mutable_params()->set_passes(1);
        pb::SubmitJobResponse response;
        grpc::Status s = stub.SubmitJob(Context().get(), request, &response);
        *id = response.job_id();
        return s;
    }
    grpc::Status Lease(const std::shared_ptr<grpc::Channel>& channel) {
        pb::LeaseTaskRequest request;
        request.set_worker_id("w");
        request.set_version(kBuildVersion);
        pb::LeaseTaskResponse response;
        return pb::WorkerService::NewStub(channel)->LeaseTask(Context().get(), request, &response);
    }
    std::vector<std::string> ListedIds(const std::string& who) {
        pb::ListJobsResponse response;
        EXPECT_TRUE(Jobs(who)->ListJobs(Context().get(), {}, &response).ok());
        std::vector<std::string> ids;
        for (const pb::Job& job : response.jobs()) ids.push_back(job.id());
        return ids;
    }

    fs::path dir_;
    JobServiceOptions service_options_;
    std::unique_ptr<Farm> farm_;
    std::unique_ptr<Authenticator> auth_;
    std::unique_ptr<JobServiceImpl> jobs_;
    std::unique_ptr<WorkerServiceImpl> workers_;
    std::unique_ptr<grpc::Server> server_;
    std::string address_;
    BlobRef scene_;
};

TEST_F(GuardedServices, SubmitterSeesOnlyItsOwnJobsAdminSeesAll) {
    std::string alice_job, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_job).ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job).ok());

    EXPECT_EQ(ListedIds("alice"), std::vector<std::string>{alice_job});
    EXPECT_EQ(ListedIds("bob"), std::vector<std::string>{bob_job});
    EXPECT_EQ(ListedIds("root"), (std::vector<std::string>{bob_job, alice_job}));

    pb::GetJobRequest get;
    get.set_job_id(alice_job);
    pb::Job job;
    ASSERT_TRUE(Jobs("alice")->GetJob(Context().get(), get, &job).ok());
    EXPECT_EQ(job.owner(), "alice");
    ASSERT_TRUE(Jobs("root")->GetJob(Context().get(), get, &job).ok());

    // Bob learns nothing of Alice's job: each call answers as for a job that does not exist.
    pb::GetJobRequest missing;
    missing.set_job_id("job-0000000000");
    const grpc::Status absent = Jobs("bob")->GetJob(Context().get(), missing, &job);
    EXPECT_EQ(absent.error_code(), grpc::StatusCode::NOT_FOUND);
    const auto expect_hidden = [&](const grpc::Status& s) {
        EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND) << s.error_message();
        EXPECT_EQ(s.error_message(), "no job " + alice_job);
    };
    auto bob = Jobs("bob");
    expect_hidden(bob->GetJob(Context().get(), get, &job));
    pb::CancelJobRequest cancel;
    cancel.set_job_id(alice_job);
    expect_hidden(bob->CancelJob(Context().get(), cancel, &job));
    pb::DeleteJobRequest del;
    del.set_job_id(alice_job);
    pb::DeleteJobResponse deleted;
    expect_hidden(bob->DeleteJob(Context().get(), del, &deleted));
    pb::FetchResultRequest fetch;
    fetch.set_job_id(alice_job);
    fetch.set_preview(true);
    {
        auto context = Context();
        auto reader = bob->FetchResult(context.get(), fetch);
        pb::Chunk chunk;
        EXPECT_FALSE(reader->Read(&chunk));
        expect_hidden(reader->Finish());
    }
    pb::WatchJobRequest watch;
    watch.set_job_id(alice_job);
    {
        auto context = Context();
        auto reader = bob->WatchJob(context.get(), watch);
        pb::Job update;
        EXPECT_FALSE(reader->Read(&update));
        expect_hidden(reader->Finish());
    }
    pb::ListTasksRequest list_tasks;
    list_tasks.set_job_id(alice_job);
    pb::ListTasksResponse tasks;
    expect_hidden(bob->ListTasks(Context().get(), list_tasks, &tasks));
    EXPECT_EQ(tasks.tasks_size(), 0);
    pb::GetTaskLogsRequest get_logs;
    get_logs.set_job_id(alice_job);
    pb::GetTaskLogsResponse logs;
    expect_hidden(bob->GetTaskLogs(Context().get(), get_logs, &logs));
    ASSERT_TRUE(Jobs("alice")->ListTasks(Context().get(), list_tasks, &tasks).ok());
    EXPECT_GT(tasks.tasks_size(), 0);
    EXPECT_TRUE(Jobs("alice")->GetTaskLogs(Context().get(), get_logs, &logs).ok());
    // Job management (issue 30): Bob can neither pause, resume nor requeue Alice's job; she
    // and the admin can.
    pb::PauseJobRequest pause;
    pause.set_job_id(alice_job);
    pb::ResumeJobRequest resume;
    resume.set_job_id(alice_job);
    pb::RequeueJobRequest requeue;
    requeue.set_job_id(alice_job);
    expect_hidden(bob->PauseJob(Context().get(), pause, &job));
    expect_hidden(bob->ResumeJob(Context().get(), resume, &job));
    expect_hidden(bob->RequeueJob(Context().get(), requeue, &job));
    ASSERT_TRUE(Jobs("alice")->PauseJob(Context().get(), pause, &job).ok());
    EXPECT_TRUE(job.paused());
    ASSERT_TRUE(Jobs("root")->ResumeJob(Context().get(), resume, &job).ok());
    EXPECT_FALSE(job.paused());
    EXPECT_TRUE(Jobs("alice")->RequeueJob(Context().get(), requeue, &job).ok());
    // Alice's own calls work, and the admin may cancel anyone's job.
    EXPECT_TRUE(Jobs("alice")->CancelJob(Context().get(), cancel, &job).ok());
    pb::CancelJobRequest cancel_bob;
    cancel_bob.set_job_id(bob_job);
    EXPECT_TRUE(Jobs("root")->CancelJob(Context().get(), cancel_bob, &job).ok());
}

// Dependencies (issue 30): `depend` is the job's owner's or an admin's, a worker's role may not,
// and another owner's job is as unknown as a dependency as it is to GetJob.
TEST_F(GuardedServices, DependenciesAreTheOwnersOrAnAdmins) {
    std::string alice_first, alice_second, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_first).ok());
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_second).ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job).ok());
    pb::AddJobDependenciesRequest depend;
    depend.set_job_id(alice_second);
    depend.add_after(alice_first);
    pb::Job job;
    const grpc::Status hidden = Jobs("bob")->AddJobDependencies(Context().get(), depend, &job);
    EXPECT_EQ(hidden.error_code(), grpc::StatusCode::NOT_FOUND) << hidden.error_message();
    EXPECT_EQ(hidden.error_message(), "no job " + alice_second);
    EXPECT_EQ(Jobs("node")->AddJobDependencies(Context().get(), depend, &job).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    ASSERT_TRUE(Jobs("alice")->AddJobDependencies(Context().get(), depend, &job).ok());
    EXPECT_EQ(job.waiting_for_size(), 1);

    pb::AddJobDependenciesRequest on_bob = depend;
    on_bob.set_after(0, bob_job);
    const grpc::Status foreign = Jobs("alice")->AddJobDependencies(Context().get(), on_bob, &job);
    EXPECT_EQ(foreign.error_code(), grpc::StatusCode::NOT_FOUND) << foreign.error_message();
    EXPECT_EQ(foreign.error_message(), "dependency " + bob_job + ": no job " + bob_job);
    ASSERT_TRUE(Jobs("root")->AddJobDependencies(Context().get(), on_bob, &job).ok())
        << "an admin sees every job";
    EXPECT_EQ(job.after_size(), 2);
    EXPECT_EQ(job.waiting_reason(),
              "waiting for " + alice_first + " (queued), " + bob_job + " (queued)");
}

// A request id is its submitter's: Bob sending Alice's gets a job of his own, not hers (he got
// her job id back, his submission was dropped and the id answered NOT_FOUND to him).
TEST_F(GuardedServices, ARequestIdIsScopedToItsOwner) {
    std::string alice_job, alice_again, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_job, "req-1").ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job, "req-1").ok());
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_again, "req-1").ok());
    EXPECT_NE(bob_job, alice_job);
    EXPECT_EQ(alice_again, alice_job) << "a retry of alice's own request is her job";
    EXPECT_EQ(ListedIds("bob"), std::vector<std::string>{bob_job});
    EXPECT_EQ(ListedIds("alice"), std::vector<std::string>{alice_job});
}

// A worker's identity is its token's and the id it claims: another token claiming the same id
// cannot keep, complete or fail that worker's lease (a token holding node1 heartbeated and
// completed node2's lease with forged pixels by claiming node2's worker_id).
TEST_F(GuardedServices, AnotherTokenCannotActForAWorkerByClaimingItsId) {
    std::string job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &job).ok());
    pb::LeaseTaskRequest lease_request;
    lease_request.set_worker_id("w");
    lease_request.set_version(kBuildVersion);
    pb::LeaseTaskResponse lease;
    ASSERT_TRUE(pb::WorkerService::NewStub(Channel("node", "worker"))
                    ->LeaseTask(Context().get(), lease_request, &lease)
                    .ok());
    ASSERT_TRUE(lease.has_task());
    auto heartbeat = [&](const std::string& who) {
        pb::HeartbeatRequest request;
        request.set_lease_id(lease.task().lease_id());
        request.set_worker_id("w");
        pb::HeartbeatResponse response;
        EXPECT_TRUE(pb::WorkerService::NewStub(Channel(who, "worker"))
                        ->Heartbeat(Context().get(), request, &response)
                        .ok());
        return !response.cancelled();
    };
    EXPECT_FALSE(heartbeat("root")) << "the lease is not root's worker's";
    EXPECT_TRUE(heartbeat("node"));
    pb::CompleteTaskRequest forged;
    forged.set_lease_id(lease.task().lease_id());
    forged.set_worker_id("w");
    pb::CompleteTaskResponse done;
    const grpc::Status s = pb::WorkerService::NewStub(Channel("root", "worker"))
                               ->CompleteTask(Context().get(), forged, &done);
    EXPECT_FALSE(s.ok());
    EXPECT_TRUE(heartbeat("node")) << "the forged result did not end node's lease";
}

TEST_F(GuardedServices, ARevokedTokensWatchStopsWithUnauthenticated) {
    std::string id;
    auto alice = Jobs("alice");
    ASSERT_TRUE(Submit(*alice, &id).ok());
    pb::WatchJobRequest watch;
    watch.set_job_id(id);
    auto context = Context();
    auto reader = alice->WatchJob(context.get(), watch);
    pb::Job update;
    ASSERT_TRUE(reader->Read(&update));
    auto tokens = TokenStore::Open((dir_ / "data").string());
    ASSERT_TRUE(tokens.ok());
    ASSERT_TRUE((*tokens)->Revoke("alice").ok());
    while (reader->Read(&update)) {
    }
    const grpc::Status s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED) << s.error_message();
    EXPECT_NE(s.error_message().find("revoked"), std::string::npos) << s.error_message();
}

// A server stream held open, its first message read, or its refusal kept.
template <class Message>
struct HeldStream {
    // Opens the stream `call` (ClientContext*) starts and reads its first message, which comes
    // once the server holds the stream's slot.
    template <class Call>
    static std::unique_ptr<HeldStream> Open(Call call) {
        auto held = std::make_unique<HeldStream>();
        held->context = std::make_unique<grpc::ClientContext>();
        held->context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
        held->reader = call(held->context.get());
        Message first;
        held->open = held->reader->Read(&first);
        if (!held->open) held->refusal = held->reader->Finish();
        return held;
    }

    std::unique_ptr<grpc::ClientContext> context;
    std::unique_ptr<grpc::ClientReader<Message>> reader;
    bool open = false;
    grpc::Status refusal;

    ~HeldStream() {
        if (!open) return;
        context->TryCancel();
        reader->Finish();
    }
};

TEST_F(GuardedServices, OneTokensWatchesLeaveRoomForAnothers) {
    std::string alice_job, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_job).ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job).ok());
    const auto watch = [](pb::JobService::Stub& stub, const std::string& id) {
        pb::WatchJobRequest request;
        request.set_job_id(id);
        return HeldStream<pb::Job>::Open(
            [&](grpc::ClientContext* context) { return stub.WatchJob(context, request); });
    };
    // Alice opens watches until she is refused, or as many as the farm serves (256).
    auto alice = Jobs("alice");
    std::vector<std::unique_ptr<HeldStream<pb::Job>>> held;
    while (held.size() < 256) {
        held.push_back(watch(*alice, alice_job));
        if (!held.back()->open) break;
    }
    ASSERT_FALSE(held.back()->open);
    EXPECT_EQ(held.back()->refusal.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(held.back()->refusal.error_message().find("--max-watchers-per-token"),
              std::string::npos)
        << held.back()->refusal.error_message();
    EXPECT_NE(held.back()->refusal.error_message().find("\"alice\""), std::string::npos)
        << held.back()->refusal.error_message();
    EXPECT_EQ(held.size(), 33u);
    auto bob = watch(*Jobs("bob"), bob_job);
    EXPECT_TRUE(bob->open) << bob->refusal.error_message();
}

TEST_F(GuardedServices, OneTokensStalledUploadsLeaveRoomForAnothers) {
    // Alice opens as many uploads as the blob store keeps partial uploads (16), each sending its
    // first 64 KiB of 1 MiB and then nothing; each ends refused or holding its partial.
    auto alice = Jobs("alice");
    struct Upload {
        grpc::ClientContext context;
        pb::UploadBlobResponse response;
        std::unique_ptr<grpc::ClientWriter<pb::UploadBlobRequest>> writer;
        std::string hash;
        std::optional<grpc::Status> refusal;
        std::thread finish;
    };
    std::vector<std::unique_ptr<Upload>> uploads;
    std::mutex mutex;
    for (int i = 0; i < kMaxPartialUploads; ++i) {
        auto up = std::make_unique<Upload>();
        up->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
        up->hash = Sha256Hex("blob " + std::to_string(i));
        up->writer = alice->UploadBlob(&up->context, &up->response);
        pb::UploadBlobRequest chunk;
        chunk.set_hash(up->hash);
        chunk.set_size(1 << 20);
        chunk.set_data(std::string(64 << 10, 'x'));
        up->writer->Write(chunk);
        up->finish = std::thread([&mutex, u = up.get()] {
            grpc::Status s = u->writer->Finish();
            std::lock_guard<std::mutex> lock(mutex);
            u->refusal = s;
        });
        uploads.push_back(std::move(up));
    }
    const auto settled = [&](const Upload& up) {
        std::lock_guard<std::mutex> lock(mutex);
        return up.refusal.has_value() || *farm_->blobs().UploadOffset(up.hash, 1 << 20) > 0;
    };
    for (const auto& up : uploads) {
        while (!settled(*up)) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    int refused = 0;
    {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& up : uploads) {
            if (!up->refusal) continue;
            ++refused;
            EXPECT_EQ(up->refusal->error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
            EXPECT_NE(up->refusal->error_message().find("--max-uploads-per-token"),
                      std::string::npos)
                << up->refusal->error_message();
        }
    }
    EXPECT_EQ(refused, kMaxPartialUploads - 4);

    // Bob's upload goes through while Alice's stall.
    const std::string data = "bob's texture";
    pb::UploadBlobRequest chunk;
    chunk.set_hash(Sha256Hex(data));
    chunk.set_size(data.size());
    chunk.set_data(data);
    grpc::ClientContext context;
    pb::UploadBlobResponse response;
    auto writer = Jobs("bob")->UploadBlob(&context, &response);
    writer->Write(chunk);
    writer->WritesDone();
    const grpc::Status bob = writer->Finish();
    EXPECT_TRUE(bob.ok()) << bob.error_message();
    EXPECT_TRUE(farm_->blobs().Has(Sha256Hex(data)));

    for (auto& up : uploads) {
        up->context.TryCancel();
        up->finish.join();
    }
}

// The resident memory of this process in KiB.
long ResidentKib() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
    }
    return -1;
}

TEST_F(GuardedServices, StalledResultReadersAreCappedPerTokenAndHoldNoWholeResult) {
    std::string alice_job, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_job).ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job).ok());
    // A queued job's preview is kept while no task ends: made 192 MiB here, as a large result.
    // Large beside what the transport may buffer per stream on both ends (its windows grow with
    // the measured bandwidth-delay product; 37 MB a reader was seen on a loaded machine).
    ASSERT_TRUE(farm_->ResultFile(alice_job, true).ok());
    constexpr size_t kResultBytes = size_t(192) << 20;
    {
        std::ofstream out(dir_ / "data" / "previews" / (alice_job + ".exr"), std::ios::binary);
        const std::string mebibyte(size_t(1) << 20, 'r');
        for (size_t i = 0; i < kResultBytes >> 20; ++i) out << mebibyte;
    }
    const auto fetch = [](pb::JobService::Stub& stub, const std::string& id) {
        pb::FetchResultRequest request;
        request.set_job_id(id);
        request.set_preview(true);
        return HeldStream<pb::Chunk>::Open(
            [&](grpc::ClientContext* context) { return stub.FetchResult(context, request); });
    };
    auto alice = Jobs("alice");
    const long before = ResidentKib();
    // Readers that take one chunk and stop.
    std::vector<std::unique_ptr<HeldStream<pb::Chunk>>> held;
    for (int i = 0; i < 4; ++i) {
        held.push_back(fetch(*alice, alice_job));
        ASSERT_TRUE(held.back()->open) << held.back()->refusal.error_message();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // let the server run ahead
    const long after = ResidentKib();
    // Each reader costs its chunk and what flow control lets through on both ends of the
    // connection (this process is server and client: 17 to 37 MB a reader measured), not the
    // 192 MiB result: four whole results would be 768 MiB.
    EXPECT_LT(after - before, long(4 * kResultBytes / 2 / 1024))
        << before << " KiB before, " << after << " after";
    const auto refused = fetch(*alice, alice_job);
    ASSERT_FALSE(refused->open);
    EXPECT_EQ(refused->refusal.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(refused->refusal.error_message().find("--max-fetches-per-token"), std::string::npos)
        << refused->refusal.error_message();
    // Bob's fetch goes through while Alice's readers stall.
    auto bob = fetch(*Jobs("bob"), bob_job);
    ASSERT_TRUE(bob->open) << bob->refusal.error_message();
    pb::Chunk chunk;
    while (bob->reader->Read(&chunk)) {
    }
    bob->open = false;
    const grpc::Status done = bob->reader->Finish();
    EXPECT_TRUE(done.ok()) << done.error_message();
}

TEST_F(GuardedServices, AMegabyteLongJobIdIsNotEchoedBack) {
    pb::GetJobRequest request;
    request.set_job_id(std::string(1 << 20, 'j'));
    pb::Job job;
    const grpc::Status s = Jobs("alice")->GetJob(Context().get(), request, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_LT(s.error_message().size(), 200u) << s.error_message().substr(0, 200);
}

// History (issue 30): GetStats reads as jobs do. The jobs' ends are all that is counted here
// (no worker renders): each submitter's cancelled job.
TEST_F(GuardedServices, StatsShowASubmitterItsOwnJobsAnAdminEveryonesAWorkerNone) {
    std::string alice_job, bob_job;
    ASSERT_TRUE(Submit(*Jobs("alice"), &alice_job).ok());
    ASSERT_TRUE(Submit(*Jobs("bob"), &bob_job).ok());
    pb::Job job;
    for (const std::string& id : {alice_job, bob_job}) {
        pb::CancelJobRequest cancel;
        cancel.set_job_id(id);
        ASSERT_TRUE(Jobs("root")->CancelJob(Context().get(), cancel, &job).ok());
    }
    const auto owners = [&](const std::string& who, const std::string& owner = "") {
        pb::GetStatsRequest request;
        request.set_owner(owner);
        pb::GetStatsResponse response;
        const grpc::Status s = Jobs(who)->GetStats(Context().get(), request, &response);
        std::vector<std::string> names;
        for (const pb::OwnerStats& o : response.owners()) {
            EXPECT_EQ(o.jobs_cancelled(), 1) << o.owner();
            names.push_back(o.owner());
        }
        return std::make_pair(s.error_code(), names);
    };
    using Names = std::vector<std::string>;
    EXPECT_EQ(owners("alice"), std::make_pair(grpc::StatusCode::OK, Names{"alice"}));
    EXPECT_EQ(owners("alice", "alice"), std::make_pair(grpc::StatusCode::OK, Names{"alice"}));
    EXPECT_EQ(owners("bob"), std::make_pair(grpc::StatusCode::OK, Names{"bob"}));
    EXPECT_EQ(owners("root"), std::make_pair(grpc::StatusCode::OK, Names{"alice", "bob"}));
    EXPECT_EQ(owners("root", "bob"), std::make_pair(grpc::StatusCode::OK, Names{"bob"}));
    EXPECT_EQ(owners("bob", "alice").first, grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_EQ(owners("node").first, grpc::StatusCode::PERMISSION_DENIED);

    pb::GetStatsRequest future;
    future.set_since_unix_ms(absl::ToUnixMillis(absl::Now() + absl::Hours(1)));
    pb::GetStatsResponse response;
    EXPECT_EQ(Jobs("root")->GetStats(Context().get(), future, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(GuardedServices, RolesAreKeptApart) {
    std::string id;
    const grpc::Status worker_submit = Submit(*Jobs("node"), &id);
    EXPECT_EQ(worker_submit.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_EQ(worker_submit.error_message(),
              "token \"node\" has role worker, which may not submit jobs");
    pb::ListJobsResponse list;
    EXPECT_EQ(Jobs("node")->ListJobs(Context().get(), {}, &list).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);

    // A submitter with a valid client certificate still may not lease.
    const grpc::Status submitter_lease = Lease(Channel("alice", "worker"));
    EXPECT_EQ(submitter_lease.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_EQ(Lease(Channel("node", "worker")).error_code(), grpc::StatusCode::OK);
    EXPECT_EQ(Lease(Channel("root", "worker")).error_code(), grpc::StatusCode::OK);
}

TEST_F(GuardedServices, CallsWithoutOrWithAWrongTokenAreUnauthenticated) {
    std::string id;
    const grpc::Status none = Submit(*Jobs(""), &id);
    EXPECT_EQ(none.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_NE(none.error_message().find("--token-file"), std::string::npos);
    std::ofstream(dir_ / "forged.token") << "lf1_" << std::string(64, '0') << "\n";
    const grpc::Status forged = Submit(*Jobs("forged"), &id);
    EXPECT_EQ(forged.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(Lease(Channel("", "worker")).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(GuardedServices, WorkersNeedACertificateFromTheClientCa) {
    const grpc::Status no_cert = Lease(Channel("node"));
    EXPECT_EQ(no_cert.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_NE(no_cert.error_message().find("client certificate"), std::string::npos);
    // Another CA's certificate fails the handshake: the call never reaches the service.
    const grpc::Status rogue = Lease(Channel("node", "rogue"));
    EXPECT_EQ(rogue.error_code(), grpc::StatusCode::UNAVAILABLE) << rogue.error_message();
}

TEST_F(GuardedServices, ClientThatDoesNotTrustTheServerCannotConnect) {
    auto channel = OpenChannel({.address = address_,
                                .tls_ca = (dir_ / "other.crt").string(),
                                .token_file = (dir_ / "root.token").string()});
    ASSERT_TRUE(channel.ok());
    pb::ListJobsResponse list;
    const grpc::Status s = pb::JobService::NewStub(*channel)->ListJobs(Context().get(), {}, &list);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
}

TEST(ChannelOptions, UnusableFilesAreErrorsNamingTheFlag) {
    auto missing = OpenChannel({.address = "127.0.0.1:1", .tls_ca = "/nonexistent/ca.crt"});
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().message(), "--tls-ca /nonexistent/ca.crt: cannot be read");
    auto cert_alone = OpenChannel({.address = "127.0.0.1:1", .tls_cert = "x.crt"});
    EXPECT_TRUE(absl::IsInvalidArgument(cert_alone.status()));
    const fs::path dir = testing::FreshTestDir("lf_channel");
    std::ofstream(dir / "empty.token") << "\n";
    std::ofstream(dir / "not.pem") << "hello\n";
    auto empty =
        OpenChannel({.address = "127.0.0.1:1", .token_file = (dir / "empty.token").string()});
    EXPECT_TRUE(absl::IsInvalidArgument(empty.status())) << empty.status();
    auto not_pem = OpenChannel({.address = "127.0.0.1:1", .tls_ca = (dir / "not.pem").string()});
    EXPECT_TRUE(absl::IsInvalidArgument(not_pem.status())) << not_pem.status();
    fs::remove_all(dir);
}

TEST(ServerCredentials, InconsistentTlsFlagsAreRefused) {
    EXPECT_TRUE(MakeServerCredentials({}).ok());
    EXPECT_TRUE(absl::IsInvalidArgument(MakeServerCredentials({.cert = "a.crt"}).status()));
    EXPECT_TRUE(absl::IsInvalidArgument(MakeServerCredentials({.key = "a.key"}).status()));
    EXPECT_TRUE(
        absl::IsNotFound(MakeServerCredentials({.cert = "/nonexistent.crt", .key = "k"}).status()));
}

}  // namespace
}  // namespace lf
