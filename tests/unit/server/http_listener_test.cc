// lightfarm-server --http: the /metrics and /healthz handlers against a real Farm in a temporary
// data folder (the counts follow a submission, a lease and a result), and the listener itself on
// a port the OS picks, refusing a port in use, and over HTTPS with the dashboard; hostile
// clients (a chunked body without end, slow request heads) on raw sockets; a result EXR larger
// than one piece downloaded whole from the dashboard.
#include "lf/server/http_listener.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "lf/core/film.h"
#include "lf/core/tile_codec.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class HttpListenerTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_http_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        FarmOptions options;
        options.data_dir = dir_.string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
    }
    void TearDown() override {
        farm_.reset();
        fs::remove_all(dir_);
    }

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks.
    std::string Submit() {
        JobSpec spec;
        spec.name = "metrics";
        spec.plan = {16, 16, 4, 8, 2};
        absl::StatusOr<std::string> id = farm_->scheduler().Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }

    std::string Metrics() {
        const HttpAnswer answer = MetricsAnswer(*farm_);
        EXPECT_EQ(answer.status, 200) << answer.body;
        EXPECT_EQ(answer.content_type, "text/plain; version=0.0.4; charset=utf-8");
        return answer.body;
    }

    static bool Has(const std::string& text, const std::string& line) {
        return text.find("\n" + line + "\n") != std::string::npos;
    }

    fs::path dir_;
    std::unique_ptr<Farm> farm_;
};

TEST_F(HttpListenerTest, MetricsFollowSubmissionLeaseAndResult) {
    std::string text = Metrics();
    for (const char* line :
         {"lightfarm_jobs{state=\"queued\"} 0", "lightfarm_tasks{state=\"queued\"} 0",
          "lightfarm_workers{state=\"live\"} 0", "lightfarm_queue_depth 0",
          "lightfarm_leases_total 0", "lightfarm_task_failures_total 0",
          "lightfarm_task_duration_seconds_count 0",
          "# TYPE lightfarm_store_write_seconds histogram", "# TYPE lightfarm_jobs gauge",
          "# TYPE lightfarm_leases_total counter"}) {
        EXPECT_TRUE(Has(text, line)) << line << " not in\n" << text;
    }

    const std::string job = Submit();
    text = Metrics();
    EXPECT_TRUE(Has(text, "lightfarm_jobs{state=\"queued\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_tasks{state=\"queued\"} 8")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_queue_depth 8")) << text;
    // The submission was committed before it was acknowledged.
    EXPECT_FALSE(Has(text, "lightfarm_store_write_seconds_count 0")) << text;

    const WorkerDescription about{"render-07", "ipv4:10.0.0.7:5000", "v"};
    std::optional<TaskAssignment> lease =
        farm_->scheduler().LeaseTask("w1", absl::InfinitePast(), &about);
    ASSERT_TRUE(lease);
    farm_->scheduler().LeaseTask("w2");  // a second worker, busy too
    ASSERT_TRUE(
        farm_->scheduler().Fail(lease->lease_id, "w1", "boom", FailureKind::kTaskError).ok());
    text = Metrics();
    EXPECT_TRUE(Has(text, "lightfarm_jobs{state=\"running\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_jobs{state=\"queued\"} 0")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_tasks{state=\"queued\"} 7")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_tasks{state=\"running\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_workers{state=\"live\"} 2")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_workers{state=\"busy\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_workers{state=\"idle\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_leases_total 2")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_task_failures_total 1")) << text;

    lease = farm_->scheduler().LeaseTask("w1");
    ASSERT_TRUE(lease);
    TileSums sums(lease->task.rect);
    for (PixelSums& p : sums.pixels) {
        for (uint64_t s = lease->task.sample_begin; s < lease->task.sample_end; ++s) {
            p.Add(s, Rgb(0.5f));
        }
    }
    ASSERT_TRUE(farm_->scheduler().Complete(lease->lease_id, "w1", sums).ok());
    text = Metrics();
    EXPECT_TRUE(Has(text, "lightfarm_task_duration_seconds_count 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_leases_total 3")) << text;

    ASSERT_TRUE(farm_->scheduler().Cancel(job).ok());
    text = Metrics();
    EXPECT_TRUE(Has(text, "lightfarm_jobs{state=\"cancelled\"} 1")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_jobs{state=\"running\"} 0")) << text;
    EXPECT_TRUE(Has(text, "lightfarm_tasks{state=\"queued\"} 0")) << text;
}

TEST_F(HttpListenerTest, HealthzIsOkWhileTheStoreIsUsable) {
    const HttpAnswer answer = HealthzAnswer(*farm_);
    EXPECT_EQ(answer.status, 200);
    EXPECT_EQ(answer.body, "ok\n");
}

TEST_F(HttpListenerTest, ListensOnAPortTheSystemPicksAndRefusesATakenOne) {
    absl::StatusOr<std::unique_ptr<HttpListener>> listener =
        HttpListener::Start("127.0.0.1:0", *farm_);
    ASSERT_TRUE(listener.ok()) << listener.status();
    const int port = (*listener)->port();
    ASSERT_GT(port, 0);

    httplib::Client client("127.0.0.1", port);
    client.set_connection_timeout(5);
    httplib::Result healthz = client.Get("/healthz");
    ASSERT_TRUE(healthz) << httplib::to_string(healthz.error());
    EXPECT_EQ(healthz->status, 200);
    EXPECT_EQ(healthz->body, "ok\n");
    httplib::Result metrics = client.Get("/metrics");
    ASSERT_TRUE(metrics);
    EXPECT_NE(metrics->body.find("# TYPE lightfarm_queue_depth gauge"), std::string::npos);
    EXPECT_EQ(client.Get("/nothing")->status, 404);

    const std::string taken = "127.0.0.1:" + std::to_string(port);
    absl::StatusOr<std::unique_ptr<HttpListener>> second = HttpListener::Start(taken, *farm_);
    ASSERT_FALSE(second.ok());
    EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(second.status().message().find("cannot listen on " + taken + " for --http"),
              std::string::npos)
        << second.status();
}

// A certificate of its own for 127.0.0.1, made by the openssl command (deploy/install-deps.sh
// installs it): HTTPS with the dashboard, which plain HTTP cannot reach.
TEST_F(HttpListenerTest, ServesHttpsAndTheDashboardWithTheServersCertificate) {
    const std::string cert = (dir_ / "server.crt").string(), key = (dir_ / "server.key").string();
    const std::string make =
        "openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj /CN=server -addext "
        "subjectAltName=IP:127.0.0.1 -keyout '" +
        key + "' -out '" + cert + "' >/dev/null 2>&1";
    ASSERT_EQ(std::system(make.c_str()), 0) << "openssl could not make a certificate";
    std::unique_ptr<Authenticator> auth = Authenticator::Off();
    absl::StatusOr<std::unique_ptr<HttpListener>> listener = HttpListener::Start(
        "127.0.0.1:0", *farm_, {.dashboard_auth = auth.get(), .tls_cert = cert, .tls_key = key});
    ASSERT_TRUE(listener.ok()) << listener.status();
    const int port = (*listener)->port();

    httplib::SSLClient client("127.0.0.1", port);
    client.set_ca_cert_path(cert.c_str());
    client.enable_server_certificate_verification(true);
    httplib::Result healthz = client.Get("/healthz");
    ASSERT_TRUE(healthz) << httplib::to_string(healthz.error());
    EXPECT_EQ(healthz->body, "ok\n");
    httplib::Result page = client.Get("/");
    ASSERT_TRUE(page);
    EXPECT_EQ(page->status, 200);
    EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'none'"),
              std::string::npos);
    httplib::Result jobs = client.Get("/api/jobs");
    ASSERT_TRUE(jobs);
    EXPECT_EQ(jobs->status, 200) << jobs->body;
    EXPECT_EQ(jobs->get_header_value("Content-Type"), "application/json");

    httplib::Client plain("127.0.0.1", port);
    plain.set_read_timeout(5);
    httplib::Result refused = plain.Get("/healthz");
    EXPECT_TRUE(!refused || refused->status != 200) << "plain HTTP answered on the HTTPS port";

    absl::StatusOr<std::unique_ptr<HttpListener>> bad = HttpListener::Start(
        "127.0.0.1:0", *farm_, {.tls_cert = cert, .tls_key = (dir_ / "none.key").string()});
    EXPECT_EQ(bad.status().code(), absl::StatusCode::kFailedPrecondition) << bad.status();
}

// The dashboard's EXR download is sent from the file in pieces: a result of several pieces
// arrives whole, byte for byte.
TEST_F(HttpListenerTest, AResultExrOfManyPiecesIsDownloadedWhole) {
    JobSpec spec;
    spec.name = "download";
    spec.plan = {512, 512, 1, 512, 1};  // one task
    absl::StatusOr<std::string> job = farm_->scheduler().Submit(spec);
    ASSERT_TRUE(job.ok()) << job.status();
    std::optional<TaskAssignment> lease = farm_->scheduler().LeaseTask("w1");
    ASSERT_TRUE(lease);
    TileSums sums(lease->task.rect);
    // Values that do not compress: the file stays larger than a piece.
    uint32_t state = 1;
    for (PixelSums& p : sums.pixels) {
        state = state * 1664525u + 1013904223u;
        p.Add(0, Rgb(float(state >> 8) / float(1 << 24)));
    }
    ASSERT_TRUE(farm_->Complete(lease->lease_id, "w1", EncodeTileSums(sums)).ok());
    absl::StatusOr<std::string> path = farm_->ResultFile(*job, false);
    ASSERT_TRUE(path.ok()) << path.status();
    std::ifstream in(*path, std::ios::binary);
    std::stringstream file;
    file << in.rdbuf();
    ASSERT_GT(file.str().size(), size_t(256 << 10) * 2) << "fewer than three pieces";

    std::unique_ptr<Authenticator> auth = Authenticator::Off();
    absl::StatusOr<std::unique_ptr<HttpListener>> listener =
        HttpListener::Start("127.0.0.1:0", *farm_, {.dashboard_auth = auth.get()});
    ASSERT_TRUE(listener.ok()) << listener.status();
    httplib::Client client("127.0.0.1", (*listener)->port());
    httplib::Result got = client.Get("/api/jobs/" + *job + "/result.exr");
    ASSERT_TRUE(got) << httplib::to_string(got.error());
    EXPECT_EQ(got->status, 200);
    EXPECT_EQ(got->get_header_value("Content-Type"), "image/x-exr");
    EXPECT_EQ(got->get_header_value("Content-Length"), std::to_string(file.str().size()));
    EXPECT_TRUE(got->body == file.str()) << got->body.size() << " bytes of " << file.str().size();
}

// A blocking socket connected to 127.0.0.1:`port`, whose reads give up after 10 s.
int Connect(int port) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(uint16_t(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to), 0) << strerror(errno);
    timeval ten{10, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &ten, sizeof ten);
    return fd;
}

bool Send(int fd, const std::string& bytes) {
    return send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) == ssize_t(bytes.size());
}

bool Readable(int fd) {
    pollfd p{fd, POLLIN, 0};
    return poll(&p, 1, 0) > 0;
}

// What the server sent until it closed or paused for 10 s.
std::string Answer(int fd) {
    std::string answer;
    char buffer[4096];
    for (ssize_t n; (n = recv(fd, buffer, sizeof buffer, 0)) > 0;) answer.append(buffer, n);
    return answer;
}

// The 64 KiB limit held only with Content-Length: chunks were read without end (400 MB took the
// server from 46 MB to 889 MB). Now the answer comes while the client is still sending.
TEST_F(HttpListenerTest, ChunkedBodyOverTheLimitIsRefusedBeforeItIsAllSent) {
    std::unique_ptr<Authenticator> auth = Authenticator::Off();
    absl::StatusOr<std::unique_ptr<HttpListener>> listener =
        HttpListener::Start("127.0.0.1:0", *farm_, {.dashboard_auth = auth.get()});
    ASSERT_TRUE(listener.ok()) << listener.status();
    const int port = (*listener)->port();

    const int fd = Connect(port);
    ASSERT_TRUE(Send(fd,
                     "POST /api/session HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: "
                     "application/json\r\nTransfer-Encoding: chunked\r\n\r\n"));
    const std::string chunk = "10000\r\n" + std::string(1 << 16, 'a') + "\r\n";
    constexpr int kChunks = 512;  // 32 MB
    int sent = 0;
    while (sent < kChunks && !Readable(fd) && Send(fd, chunk)) ++sent;
    const std::string answer = Answer(fd);
    close(fd);
    EXPECT_LT(sent, kChunks) << "the server read all " << kChunks << " chunks";
    EXPECT_EQ(answer.substr(0, 12), "HTTP/1.1 413") << answer;

    // A small chunked body is read as before.
    httplib::Client client("127.0.0.1", port);
    client.set_read_timeout(10);
    httplib::Result small = client.Post(
        "/api/session",
        [](size_t, httplib::DataSink& sink) {
            sink.write("{\"token\": \"x\"}", 14);
            sink.done();
            return true;
        },
        "application/json");
    ASSERT_TRUE(small) << httplib::to_string(small.error());
    EXPECT_NE(small->status, 413);
}

// Slowloris: 17 connections sending a header line every 3 s held the 16 handler threads, and
// /healthz went unanswered. Now heads are read apart from the handler threads, and /healthz
// has a thread of its own.
TEST_F(HttpListenerTest, HealthzAnswersWhileMoreSlowClientsThanThreadsSendHeads) {
    absl::StatusOr<std::unique_ptr<HttpListener>> listener =
        HttpListener::Start("127.0.0.1:0", *farm_);
    ASSERT_TRUE(listener.ok()) << listener.status();
    const int port = (*listener)->port();

    std::vector<int> slow;
    for (int i = 0; i < 40; ++i) {
        slow.push_back(Connect(port));
        Send(slow.back(), "GET /metrics HTTP/1.1\r\n");
    }
    std::atomic<bool> done = false;
    std::thread sender([&] {
        for (int line = 0; !done; ++line) {
            for (int fd : slow) Send(fd, "X-Slow-" + std::to_string(line) + ": 1\r\n");
            std::this_thread::sleep_for(std::chrono::milliseconds(500));
        }
    });
    std::this_thread::sleep_for(std::chrono::seconds(1));

    httplib::Client client("127.0.0.1", port);
    client.set_connection_timeout(5);
    client.set_read_timeout(5);
    httplib::Result healthz = client.Get("/healthz");
    done = true;
    sender.join();
    for (int fd : slow) close(fd);
    ASSERT_TRUE(healthz) << httplib::to_string(healthz.error());
    EXPECT_EQ(healthz->status, 200);
    EXPECT_EQ(healthz->body, "ok\n");
}

// The read timeout was renewed by every line: a head sent a line at a time never ended. Now the
// whole request has a deadline: 408, and the connection closed, while the client still sends.
TEST_F(HttpListenerTest, ARequestHeadThatNeverEndsIsCutOff) {
    absl::StatusOr<std::unique_ptr<HttpListener>> listener =
        HttpListener::Start("127.0.0.1:0", *farm_, {.request_read_time = absl::Seconds(2)});
    ASSERT_TRUE(listener.ok()) << listener.status();

    const int fd = Connect((*listener)->port());
    bool cut_off = !Send(fd, "GET /healthz HTTP/1.1\r\n");
    for (int line = 0; line < 120 && !cut_off; ++line) {  // 30 s of lines
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
        cut_off = Readable(fd) || !Send(fd, "X-Slow: " + std::to_string(line) + "\r\n");
    }
    const std::string answer = Answer(fd);
    close(fd);
    EXPECT_TRUE(cut_off);
    EXPECT_EQ(answer.substr(0, 12), "HTTP/1.1 408") << answer;
}

TEST_F(HttpListenerTest, RefusesAnAddressWithoutAPort) {
    EXPECT_EQ(HttpListener::Start("localhost", *farm_).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(HttpListener::Start("localhost:http", *farm_).status().code(),
              absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
