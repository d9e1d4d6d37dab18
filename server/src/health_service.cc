#include "lf/server/health_service.h"

#include <grpcpp/support/byte_buffer.h>

#include <optional>
#include <string>

namespace lf {

namespace {

// Answers one status (HealthCheckResponse{status}: field 1 as a varint, SERVING 1 and
// NOT_SERVING 2) and ends the call; or ends it UNIMPLEMENTED. The request is never read.
class OneAnswer final : public grpc::ServerGenericBidiReactor {
  public:
    explicit OneAnswer(std::optional<bool> serving) {
        if (!serving) {
            Finish(grpc::Status(grpc::StatusCode::UNIMPLEMENTED, ""));
            return;
        }
        const char bytes[2] = {0x08, char(*serving ? 1 : 2)};
        grpc::Slice slice(bytes, sizeof bytes);
        answer_ = grpc::ByteBuffer(&slice, 1);
        StartWriteAndFinish(&answer_, grpc::WriteOptions(), grpc::Status::OK);
    }
    void OnDone() override { delete this; }

  private:
    grpc::ByteBuffer answer_;
};

}  // namespace

grpc::ServerGenericBidiReactor* HealthService::CreateReactor(
    grpc::GenericCallbackServerContext* context) {
    const std::string& method = context->method();
    const bool health =
        method == "/grpc.health.v1.Health/Check" || method == "/grpc.health.v1.Health/Watch";
    return new OneAnswer(health ? std::optional<bool>(serving_) : std::nullopt);
}

}  // namespace lf
