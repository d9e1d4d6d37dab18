#include "lf/worker/server_connection.h"

#include <grpcpp/grpcpp.h>

#include <fstream>

#include "lf/job/plan.h"
#include "lf/job/splat_settings.h"
#include "lf/proto/connection_status.h"
#include "lf/proto/grpc_status.h"
#include "lf/version.h"
#include "lf/wire/conversions.h"
#include "lightfarm/v1/worker_service.grpc.pb.h"

namespace lf {

namespace pb = lightfarm::v1;

struct ServerConnection::Stub {
    ChannelOptions options;  // for messages: the address, and whether TLS is on
    std::shared_ptr<grpc::Channel> channel;
    std::unique_ptr<pb::WorkerService::Stub> stub;
};

ServerConnection::ServerConnection(std::string worker_id, std::string name)
    : worker_id_(std::move(worker_id)), name_(std::move(name)), stub_(std::make_unique<Stub>()) {}

absl::StatusOr<std::unique_ptr<ServerConnection>> ServerConnection::Open(
    const ChannelOptions& options, std::string worker_id, std::string name) {
    grpc::ChannelArguments args;
    // gRPC's default reconnect backoff grows to two minutes; a restarted server should get its
    // workers back at once.
    args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
    args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
    args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
    // The coordinator takes results up to this (splat tasks' splats: docs/farm.md).
    args.SetMaxSendMessageSize(kMaxTaskResultBytes);
    // A lease carries the job's spec and may carry a radiosity sweep's input.
    args.SetMaxReceiveMessageSize(int(kMaxLeaseBytes));
    absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = OpenChannel(options, args);
    if (!channel.ok()) return channel.status();
    std::unique_ptr<ServerConnection> connection(
        new ServerConnection(std::move(worker_id), std::move(name)));
    connection->stub_->options = options;
    connection->stub_->channel = *channel;
    connection->stub_->stub = pb::WorkerService::NewStub(*channel);
    return connection;
}

ServerConnection::~ServerConnection() = default;

absl::StatusOr<std::optional<TaskAssignment>> ServerConnection::Lease(absl::Duration wait) {
    pb::LeaseTaskRequest req;
    req.set_worker_id(worker_id_);
    req.set_wait_ms(int(absl::ToInt64Milliseconds(wait)));
    req.set_version(kBuildVersion);
    req.set_name(name_);
    for (const std::string& tag : tags_) req.add_tags(tag);
    pb::LeaseTaskResponse resp;
    // Waiting for the connection (rather than failing at once while the channel is in
    // backoff) is what makes the channel reconnect as soon as a restarted server listens.
    const auto context = ContextWithDeadline(wait + absl::Seconds(1));
    context->set_wait_for_ready(true);
    grpc::Status s = stub_->stub->LeaseTask(context.get(), req, &resp);
    // Waiting hides why the connection fails ("Deadline Exceeded"); a call that does not wait
    // says it (TLS on one side only, say).
    if (s.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED &&
        stub_->channel->GetState(false) != GRPC_CHANNEL_READY) {
        req.set_wait_ms(0);
        s = stub_->stub->LeaseTask(ContextWithDeadline(absl::Seconds(1)).get(), req, &resp);
    }
    if (!s.ok()) return ConnectionStatus(s, stub_->options);
    if (!resp.has_task()) return std::nullopt;
    return FromProto(resp.task());
}

absl::StatusOr<bool> ServerConnection::Heartbeat(const std::string& lease_id,
                                                 std::vector<TaskLogLine> log) {
    pb::HeartbeatRequest req;
    req.set_lease_id(lease_id);
    req.set_worker_id(worker_id_);
    for (const TaskLogLine& line : log) ToProto(line, req.add_log());
    pb::HeartbeatResponse resp;
    const grpc::Status s =
        stub_->stub->Heartbeat(ContextWithDeadline(absl::Seconds(2)).get(), req, &resp);
    if (!s.ok()) return FromGrpcStatus(s);
    return !resp.cancelled();
}

absl::Status ServerConnection::Complete(const std::string& lease_id, const TaskResult& result,
                                        double seconds) {
    pb::CompleteTaskRequest req;
    req.set_lease_id(lease_id);
    req.set_worker_id(worker_id_);
    (result.sweep ? req.mutable_radiosity_sweep() : req.mutable_tile_sums())->assign(result.bytes);
    req.set_seconds(seconds);
    req.set_cpu_seconds(result.times.cpu_seconds);
    if (result.radiosity) ToProto(*result.radiosity, req.mutable_radiosity());
    if (result.splats) req.set_splats(*result.splats);
    if (result.frame) req.set_frame(*result.frame);
    for (const TaskResult::Part& part : result.parts) {
        pb::TaskPartResult* p = req.add_parts();
        p->set_frame(part.frame);
        p->set_tile_sums(part.bytes);
        if (part.splats) p->set_splats(*part.splats);
        p->set_render_seconds(part.times.render_seconds);
        p->set_cpu_seconds(part.times.cpu_seconds);
    }
    for (const TaskLogLine& line : result.log) ToProto(line, req.add_log());
    pb::CompleteTaskResponse resp;
    // Rides out a server restart: the result stays valid after its lease.
    const auto context = ContextWithDeadline(absl::Seconds(30));
    context->set_wait_for_ready(true);
    return FromGrpcStatus(stub_->stub->CompleteTask(context.get(), req, &resp));
}

absl::Status ServerConnection::Fail(const std::string& lease_id, const std::string& reason,
                                    bool shutdown, std::vector<TaskLogLine> log) {
    pb::FailTaskRequest req;
    req.set_lease_id(lease_id);
    req.set_worker_id(worker_id_);
    req.set_reason(reason);
    req.set_kind(shutdown ? pb::FailTaskRequest::WORKER_SHUTDOWN : pb::FailTaskRequest::TASK_ERROR);
    for (const TaskLogLine& line : log) ToProto(line, req.add_log());
    pb::FailTaskResponse resp;
    return FromGrpcStatus(
        stub_->stub->FailTask(ContextWithDeadline(absl::Seconds(5)).get(), req, &resp));
}

absl::Status ServerConnection::FetchBlob(const std::string& hash, const std::string& path) {
    pb::FetchBlobRequest req;
    req.set_hash(hash);
    // Generous: a large mesh over a slow link.
    const auto context = ContextWithDeadline(absl::Minutes(10));
    std::unique_ptr<grpc::ClientReader<pb::Chunk>> reader =
        stub_->stub->FetchBlob(context.get(), req);
    std::ofstream out(path, std::ios::binary);
    pb::Chunk chunk;
    while (reader->Read(&chunk))
        out.write(chunk.data().data(), std::streamsize(chunk.data().size()));
    const grpc::Status s = reader->Finish();
    if (!s.ok()) return FromGrpcStatus(s);
    out.close();
    if (!out) return absl::InternalError(path + ": write failed");
    return absl::OkStatus();
}

}  // namespace lf
