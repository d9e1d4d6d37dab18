// --grpc-health: a plain-text port that answers grpc.health.v1.Health/Check as a probe asks
// (an empty service name), SERVING until shutdown begins, then NOT_SERVING.
#include "lf/server/health_port.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <gtest/gtest.h>

namespace lf {
namespace {

// Health/Check for service "", by hand: the request is the empty message and the answer
// HealthCheckResponse{status} is field 1 as a varint (SERVING 1, NOT_SERVING 2).
int CheckStatus(const std::string& address) {
    grpc::GenericStub stub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    grpc::ByteBuffer request, response;
    grpc::Slice empty("");
    request = grpc::ByteBuffer(&empty, 1);
    grpc::Status status;
    std::mutex mutex;
    std::condition_variable done_cv;
    bool done = false;
    stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request,
                   &response, [&](grpc::Status s) {
                       std::lock_guard<std::mutex> lock(mutex);
                       status = s;
                       done = true;
                       done_cv.notify_one();
                   });
    std::unique_lock<std::mutex> lock(mutex);
    done_cv.wait(lock, [&] { return done; });
    EXPECT_TRUE(status.ok()) << status.error_message();
    std::vector<grpc::Slice> slices;
    EXPECT_TRUE(response.Dump(&slices).ok());
    std::string bytes;
    for (const grpc::Slice& s : slices)
        bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
    if (bytes.size() != 2 || bytes[0] != 0x08) return -1;
    return bytes[1];
}

TEST(HealthPort, ServingUntilShutdownBeginsThenNotServing) {
    absl::StatusOr<HealthPort> health = StartHealthPort("127.0.0.1:0");
    ASSERT_TRUE(health.ok()) << health.status();
    const std::string address = "127.0.0.1:" + std::to_string(health->port);
    EXPECT_EQ(CheckStatus(address), 1);
    health->health->SetServing(false);
    EXPECT_EQ(CheckStatus(address), 2);
    health->server->Shutdown(std::chrono::system_clock::now());
}

TEST(HealthPort, PortInUseIsAnErrorNamingIt) {
    absl::StatusOr<HealthPort> first = StartHealthPort("127.0.0.1:0");
    ASSERT_TRUE(first.ok());
    const std::string taken = "127.0.0.1:" + std::to_string(first->port);
    absl::StatusOr<HealthPort> second = StartHealthPort(taken);
    ASSERT_FALSE(second.ok());
    EXPECT_NE(second.status().message().find(taken + " for --grpc-health"), std::string::npos)
        << second.status();
    first->server->Shutdown(std::chrono::system_clock::now());
}

}  // namespace
}  // namespace lf
