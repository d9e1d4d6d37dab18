// The cost of TLS and tokens on the wire: against a running lightfarm-server, the time of a new
// connection's first call (TCP connect, TLS handshake when --tls-ca is given, one ListJobs) and
// of a call on an open connection (ListJobs of one job), as minimum, median and 90th percentile.
// Run it against one server with TLS and one without to read the overhead (docs/farm.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "lightfarm/v1/job_service.grpc.pb.h"
#include "lf/proto/channel.h"
#include "lf/proto/channel_flags.h"
#include "lf/proto/grpc_status.h"

namespace pb = lightfarm::v1;

namespace {

using Clock = std::chrono::steady_clock;

// One ListJobs call of one job: the smallest call that passes the token check and the store.
double TimedCall(pb::JobService::Stub& stub, bool* ok) {
    pb::ListJobsRequest req;
    req.set_page_size(1);
    pb::ListJobsResponse resp;
    const auto start = Clock::now();
    const grpc::Status s =
        stub.ListJobs(lf::ContextWithDeadline(absl::Seconds(10)).get(), req, &resp);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (!s.ok()) {
        std::fprintf(stderr, "rpc_bench: ListJobs: %s\n", s.error_message().c_str());
        *ok = false;
    }
    return ms;
}

void Print(const char* what, std::vector<double> ms) {
    std::sort(ms.begin(), ms.end());
    std::printf("%-26s n=%-5zu min %.3f ms  median %.3f ms  p90 %.3f ms\n", what, ms.size(),
                ms.front(), ms[ms.size() / 2], ms[ms.size() * 9 / 10]);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"rpc_bench: connection and per-call times of lightfarm-server's JobService"};
    lf::ChannelOptions channel{.address = "127.0.0.1:7070"};
    int connections = 50, calls = 1000;
    app.add_option("--server", channel.address, "HOST:PORT")->capture_default_str();
    lf::AddChannelFlags(&app, &channel);
    app.add_option("--connections", connections, "new connections to time")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    app.add_option("--calls", calls, "calls on one connection to time")
        ->capture_default_str()
        ->check(CLI::Range(1, 10000000));
    CLI11_PARSE(app, argc, argv);

    bool ok = true;
    std::vector<double> connect_ms, call_ms;
    for (int i = 0; i < connections && ok; ++i) {
        grpc::ChannelArguments args;
        args.SetInt("lightfarm.rpc_bench.connection", i);  // a new connection each time
        absl::StatusOr<std::shared_ptr<grpc::Channel>> c = lf::OpenChannel(channel, args);
        if (!c.ok()) {
            std::fprintf(stderr, "rpc_bench: %s\n", std::string(c.status().message()).c_str());
            return 2;
        }
        connect_ms.push_back(TimedCall(*pb::JobService::NewStub(*c), &ok));
    }
    absl::StatusOr<std::shared_ptr<grpc::Channel>> c = lf::OpenChannel(channel);
    const auto stub = pb::JobService::NewStub(*c);
    TimedCall(*stub, &ok);  // connects
    for (int i = 0; i < calls && ok; ++i) call_ms.push_back(TimedCall(*stub, &ok));
    if (!ok) return 1;
    std::printf(
        "server %s, %s, %s\n", channel.address.c_str(), channel.tls_ca.empty() ? "no TLS" : "TLS",
        channel.token_file.empty() && !std::getenv("LIGHTFARM_TOKEN") ? "no token" : "token");
    Print("new connection + 1st call", connect_ms);
    Print("call on open connection", call_ms);
    return 0;
}
