// grpc.health.v1.Health without reading requests: Check answers the server's state, SERVING
// until SetServing(false), then NOT_SERVING; Watch answers it once and ends; every other method
// not registered on the server answers UNIMPLEMENTED.
//
// gRPC's default health service reads each request whole before it answers, and health needs no
// token, so one probe announcing 200 MB made the server hold them (gRPC 1.51 buffers a message
// before its size limit applies, grpc/grpc#43012). This one never reads: the service name a
// request may carry is not looked at, and every name answers the server's state, as "" does.
//
// It is a sync service, as the coordinator's others are. A callback service (gRPC's default
// health service is one) starts gRPC's callback threads beside the sync server's, and then the
// coordinator took a worker's call up to 90 ms late, in about half the Cornell box jobs on two
// cores (tools/radiosity_bench.md, "A health service without callbacks").
#pragma once

#include <grpcpp/impl/service_type.h>

#include <atomic>

namespace lf {

class HealthService final : public grpc::Service {
  public:
    // A sync handler holds a server thread until its answer is sent, and a client that opens no
    // HTTP/2 window holds it until the client goes: 300 such calls held 300 threads. Beyond this
    // many at once, a call answers UNAVAILABLE at once (a status, which no window holds back).
    static constexpr int kMaxCallsInFlight = 32;

    HealthService();

    void SetServing(bool serving) { serving_ = serving; }
    bool serving() const { return serving_; }

  private:
    std::atomic<bool> serving_{true};
    std::atomic<int> in_flight_{0};
};

}  // namespace lf
