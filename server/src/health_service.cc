#include "lf/server/health_service.h"

#include <grpcpp/impl/rpc_service_method.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/method_handler.h>
#include <grpcpp/support/sync_stream.h>

namespace lf {

namespace {

// HealthCheckResponse{status}: field 1 as a varint, SERVING 1 and NOT_SERVING 2.
grpc::ByteBuffer Answer(bool serving) {
    const char bytes[2] = {0x08, char(serving ? 1 : 2)};
    grpc::Slice slice(bytes, sizeof bytes);
    return grpc::ByteBuffer(&slice, 1);
}

}  // namespace

HealthService::HealthService() {
    using grpc::ByteBuffer;
    using grpc::internal::RpcMethod;
    // As bidi streams whose handler writes the answer and ends: the request is never read (a
    // unary or split streamer would not write before it read), and a unary client takes the one
    // message as its answer.
    for (const char* method : {"/grpc.health.v1.Health/Check", "/grpc.health.v1.Health/Watch"}) {
        AddMethod(new grpc::internal::RpcServiceMethod(
            method, RpcMethod::BIDI_STREAMING,
            new grpc::internal::BidiStreamingHandler<HealthService, ByteBuffer, ByteBuffer>(
                [](HealthService* self, grpc::ServerContext*,
                   grpc::ServerReaderWriter<ByteBuffer, ByteBuffer>* call) {
                    struct InFlight {
                        std::atomic<int>& n;
                        ~InFlight() { --n; }
                    } counted{self->in_flight_};
                    if (++self->in_flight_ > kMaxCallsInFlight) {
                        return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                            "too many health checks at once");
                    }
                    call->Write(Answer(self->serving()));
                    return grpc::Status::OK;
                },
                this)));
    }
}

}  // namespace lf
