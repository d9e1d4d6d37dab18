#pragma once

// Request messages are read only after the caller's token and role are checked.
//
// gRPC 1.51's HTTP/2 transport buffers a whole request message before any handler runs, and
// enforces the receive limit only once the last byte arrived (grpc/grpc#43012): three calls
// without a token, each announcing 300 MB, held 1.9 GB. So every unary and server-streaming
// method is registered as "streamed": its handler runs on the call's metadata alone, the guard
// checks the token there, and only then is the one request read (a refused call's bytes are
// dropped with the stream, never buffered beyond HTTP/2's window). A request read is refused above
// its method's bound, which is kMaxRequestBytes for all but CompleteTask.

#include <google/protobuf/descriptor.h>
#include <grpcpp/impl/codegen/method_handler.h>
#include <grpcpp/support/sync_stream.h>

#include <cstddef>
#include <functional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "lf/job/plan.h"
#include "lf/proto/grpc_status.h"
#include "lf/server/auth.h"

namespace lf {

// The largest request of any call but a worker's task result (CompleteTask): job specs, lists and
// heartbeats are a few kB; scenes travel as blobs in chunks of 1 MiB.
inline constexpr size_t kMaxRequestBytes = size_t(4) << 20;
// A lease holds what such a request submitted, and a sweep's input: the workers take that much.
static_assert(kMaxRequestBytes + kMaxInlineRadiosityBytes + (size_t(1) << 20) <= kMaxLeaseBytes);

struct CallGuard {
    Authenticator& auth;
    // With mutual TLS (lightfarm-server --tls-client-ca): WorkerService calls must come with a
    // client certificate the CA signed, besides a worker token.
    bool worker_certificates = false;

    // The caller of `rpc` if it may take `action`; UNAUTHENTICATED or PERMISSION_DENIED with the
    // reason otherwise, and the refusal logged with the peer.
    absl::StatusOr<Caller> Check(grpc::ServerContext* context, const char* rpc,
                                 Action action) const;
};

// RESOURCE_EXHAUSTED naming the call and the bound when a request of `bytes` is above it.
absl::Status CheckRequestSize(const char* rpc, size_t bytes, size_t max_bytes);

// A generated sync service (`Generated`, e.g. JobService::Service) whose methods are registered
// by Unary and ServerStreaming to run their handler with the checked caller.
template <class Generated>
class ReadAfterAuth : public Generated {
  public:
    template <class Req, class Resp>
    using UnaryHandler =
        std::function<grpc::Status(grpc::ServerContext*, const Caller&, const Req&, Resp*)>;
    template <class Req, class Resp>
    using StreamingHandler = std::function<grpc::Status(
        grpc::ServerContext*, const Caller&, const Req&, const std::function<bool(const Resp&)>&)>;

  protected:
    ReadAfterAuth(const char* service, CallGuard guard) : guard_(guard), service_(service) {}

    template <class Req, class Resp>
    void Unary(const char* rpc, Action action, size_t max_request_bytes,
               UnaryHandler<Req, Resp> handler) {
        this->MarkMethodStreamed(
            MethodIndex(rpc),
            new grpc::internal::StreamedUnaryHandler<Req, Resp>(
                [guard = guard_, rpc, action, max_request_bytes, handler = std::move(handler)](
                    grpc::ServerContext* context, grpc::ServerUnaryStreamer<Req, Resp>* stream) {
                    Req req;
                    absl::StatusOr<Caller> caller =
                        ReadChecked(guard, context, rpc, action, max_request_bytes, stream, req);
                    if (!caller.ok()) return ToGrpcStatus(caller.status());
                    Resp resp;
                    grpc::Status status = handler(context, *caller, req, &resp);
                    if (status.ok()) stream->Write(resp);
                    return status;
                }));
    }

    template <class Req, class Resp>
    void ServerStreaming(const char* rpc, Action action, StreamingHandler<Req, Resp> handler) {
        this->MarkMethodStreamed(
            MethodIndex(rpc),
            new grpc::internal::SplitServerStreamingHandler<Req, Resp>(
                [guard = guard_, rpc, action, handler = std::move(handler)](
                    grpc::ServerContext* context, grpc::ServerSplitStreamer<Req, Resp>* stream) {
                    Req req;
                    absl::StatusOr<Caller> caller =
                        ReadChecked(guard, context, rpc, action, kMaxRequestBytes, stream, req);
                    if (!caller.ok()) return ToGrpcStatus(caller.status());
                    return handler(context, *caller, req, [stream](const Resp& message) {
                        return stream->Write(message);
                    });
                }));
    }

    const CallGuard guard_;

  private:
    template <class Stream, class Req>
    static absl::StatusOr<Caller> ReadChecked(const CallGuard& guard, grpc::ServerContext* context,
                                              const char* rpc, Action action,
                                              size_t max_request_bytes, Stream* stream, Req& req) {
        absl::StatusOr<Caller> caller = guard.Check(context, rpc, action);
        if (!caller.ok()) return caller.status();
        if (!stream->Read(&req)) {
            return absl::CancelledError(absl::StrCat(rpc, ": the call ended before its request"));
        }
        if (absl::Status s = CheckRequestSize(rpc, req.ByteSizeLong(), max_request_bytes);
            !s.ok()) {
            return s;
        }
        return caller;
    }

    // The generated code numbers methods in the order the .proto declares them.
    int MethodIndex(const char* rpc) const {
        const google::protobuf::ServiceDescriptor* service =
            google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(service_);
        const google::protobuf::MethodDescriptor* method =
            service ? service->FindMethodByName(rpc) : nullptr;
        if (!method) throw std::logic_error(absl::StrCat("no method ", service_, ".", rpc));
        return method->index();
    }

    const std::string service_;
};

}  // namespace lf
