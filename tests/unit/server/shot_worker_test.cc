// A shot rendered end to end in this process: the coordinator (Farm behind gRPC) and a real
// worker posing the scene per frame. A triangle a glTF animation moves gives frames that differ,
// and the same bits whether each frame's tiles spread over tasks or a task renders whole frames
// (--chunk); a scene without animation gives every frame the still's bits.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "absl/strings/escaping.h"
#include "lf/core/image_io.h"
#include "lf/job/digest.h"
#include "lf/server/grpc_service.h"
#include "lf/worker/worker.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// A triangle lit by its own emission, moved 1 unit along +x over its 1 s animation, seen by a
// camera 3 units away.
std::string MovingTriangleGltf() {
    std::string buffer;
    const auto put = [&](std::initializer_list<float> values) {
        for (float v : values) buffer.append(reinterpret_cast<const char*>(&v), sizeof v);
    };
    put({-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0, 0.5f, 0});  // 36 bytes
    put({0, 1});                                         // 8
    put({0, 0, 0, 1, 0, 0});                             // 24
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.333}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
  "materials": [{"emissiveFactor": [1, 1, 1],
                 "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}}],
  "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                  "samplers": [{"input": 1, "output": 2, "interpolation": "LINEAR"}]}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
    {"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 8},
                  {"buffer": 0, "byteOffset": 44, "byteLength": 24}],
  "buffers": [{"byteLength": 68, "uri": "data:application/octet-stream;base64,)" +
           absl::Base64Escape(buffer) + R"("}]})";
}

std::string ReadText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

class ShotWorkerTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_shotworker");
        FarmOptions options;
        options.data_dir = (dir_ / "server").string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        service_ = std::make_unique<WorkerServiceImpl>(*farm_, CallGuard{*auth_});
        grpc::ServerBuilder builder;
        int port = 0;
        builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
        builder.RegisterService(service_.get());
        server_ = builder.BuildAndStart();
        ASSERT_TRUE(server_ && port > 0);
        absl::StatusOr<std::unique_ptr<BlobCache>> cache =
            BlobCache::Open((dir_ / "cache").string(), 1 << 24);
        ASSERT_TRUE(cache.ok()) << cache.status();
        cache_ = std::move(*cache);
        absl::StatusOr<std::unique_ptr<ServerConnection>> connection =
            ServerConnection::Open({.address = "127.0.0.1:" + std::to_string(port)}, "w1");
        ASSERT_TRUE(connection.ok()) << connection.status();
        connection_ = std::move(*connection);
        WorkerOptions worker_options;
        worker_options.threads = 2;
        worker_ = std::make_unique<Worker>(worker_options, *connection_, *cache_, logs_);
        run_ = std::thread([this] { worker_->Run(); });
    }

    void TearDown() override {
        worker_->Stop();
        run_.join();
        worker_.reset();
        farm_->scheduler().Shutdown();
        server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
        fs::remove_all(dir_);
    }

    BlobRef Put(const std::string& path, const std::string& content) {
        auto upload = farm_->blobs().StartUpload(Sha256Hex(content), content.size());
        EXPECT_TRUE(upload.ok()) << upload.status();
        EXPECT_TRUE((*upload)->Append(content).ok());
        EXPECT_TRUE((*upload)->Finish().ok());
        return {path, Sha256Hex(content), content.size()};
    }

    JobSpec Spec(const BlobRef& scene, std::optional<FrameRange> frames, int chunk = 1) {
        JobSpec spec;
        spec.scene = scene;
        spec.scene_options.width = 16;
        spec.scene_options.height = 12;
        spec.plan = {.spp = 4, .tile = 8, .passes = 1};
        spec.shot.frames = frames;
        spec.shot.fps = 4;
        spec.shot.chunk = chunk;
        return spec;
    }

    // Submits `spec` and waits for it to end; its record.
    JobRecord Render(const JobSpec& spec) {
        absl::StatusOr<std::string> id = farm_->Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        if (!id.ok()) return {};
        const absl::Time deadline = absl::Now() + absl::Seconds(120);
        uint64_t version = 0;
        while (absl::Now() < deadline) {
            absl::StatusOr<JobRecord> job = farm_->scheduler().Get(*id);
            if (job.ok() && IsFinal(job->state)) return *job;
            version = farm_->scheduler().WaitForChange(version, absl::Now() + absl::Seconds(1));
        }
        ADD_FAILURE() << "job " << *id << " did not end";
        return {};
    }

    Image FrameOf(const JobRecord& job, std::optional<int> frame) {
        absl::StatusOr<std::string> path = farm_->ResultFile(job.id, false, frame);
        EXPECT_TRUE(path.ok()) << path.status();
        absl::StatusOr<ExrFile> exr = ReadExr(path.ok() ? *path : "");
        EXPECT_TRUE(exr.ok()) << exr.status();
        return exr.ok() ? exr->image : Image{};
    }

    fs::path dir_;
    std::unique_ptr<Authenticator> auth_ = Authenticator::Off();
    std::unique_ptr<Farm> farm_;
    std::unique_ptr<WorkerServiceImpl> service_;
    std::unique_ptr<grpc::Server> server_;
    std::unique_ptr<BlobCache> cache_;
    std::unique_ptr<ServerConnection> connection_;
    TaskLogSink logs_;
    std::unique_ptr<Worker> worker_;
    std::thread run_;
};

TEST_F(ShotWorkerTest, AMovingTriangleGivesFramesThatDifferAndChunksGiveTheSameBits) {
    const BlobRef scene = Put("moving.gltf", MovingTriangleGltf());
    const JobRecord tiles = Render(Spec(scene, FrameRange{0, 3, 1}));
    ASSERT_EQ(tiles.state, JobState::kSucceeded) << tiles.error;
    const JobRecord chunks = Render(Spec(scene, FrameRange{0, 3, 1}, 3));
    ASSERT_EQ(chunks.state, JobState::kSucceeded) << chunks.error;
    EXPECT_EQ(chunks.tasks_total, 2);
    // History (issue 30): each frame of a chunk has its part's own times, within its lease's.
    ASSERT_EQ(chunks.frames.size(), 4u);
    double frames_render = 0;
    for (const FrameProgress& f : chunks.frames) {
        EXPECT_GT(f.times.render_seconds, 0) << "frame " << f.frame;
        EXPECT_GE(f.times.cpu_seconds, 0) << "frame " << f.frame;
        frames_render += f.times.render_seconds;
    }
    EXPECT_LE(frames_render, chunks.times.render_seconds);
    EXPECT_GT(chunks.times.cpu_seconds, 0);
    std::vector<std::vector<float>> red;
    for (int f = 0; f < 4; ++f) {
        const Image a = FrameOf(tiles, f), b = FrameOf(chunks, f);
        ASSERT_TRUE(a.FindChannel("R") && b.FindChannel("R")) << f;
        EXPECT_EQ(*a.FindChannel("R"), *b.FindChannel("R")) << "frame " << f;
        EXPECT_EQ(*a.FindChannel("A.G"), *b.FindChannel("A.G")) << "frame " << f;
        red.push_back(*a.FindChannel("R"));
    }
    float lit = 0;
    for (float v : red[0]) lit += v;
    EXPECT_GT(lit, 0) << "the triangle is seen";
    for (int f = 1; f < 4; ++f) EXPECT_NE(red[size_t(f)], red[0]) << "frame " << f << " moved";
}

// Splatting methods' chunks: a frame's tasks add their splats to one list on the worker (so a
// chunk's result holds at most one list a frame); the frames are the bits of one task a lease.
TEST_F(ShotWorkerTest, SplattingChunksSumTheirFramesSplatsToTheSameBits) {
    const BlobRef scene = Put("moving.gltf", MovingTriangleGltf());
    for (const char* method : {"light", "bdpt"}) {
        SCOPED_TRACE(method);
        JobSpec spec = Spec(scene, FrameRange{0, 1, 1});
        spec.method = method;
        spec.plan.passes = 2;
        const JobRecord tasks = Render(spec);
        ASSERT_EQ(tasks.state, JobState::kSucceeded) << tasks.error;
        ASSERT_GT(tasks.tasks_total, 2) << "several tasks a frame, so a chunk sums their splats";
        spec.shot.chunk = 2;
        const JobRecord chunk = Render(spec);
        ASSERT_EQ(chunk.state, JobState::kSucceeded) << chunk.error;
        EXPECT_EQ(chunk.tasks_total, 1) << "one task renders both frames";
        for (int f = 0; f < 2; ++f) {
            const Image a = FrameOf(tasks, f), b = FrameOf(chunk, f);
            ASSERT_TRUE(a.FindChannel("R") && b.FindChannel("R")) << f;
            EXPECT_EQ(*a.FindChannel("R"), *b.FindChannel("R")) << "frame " << f;
            EXPECT_EQ(*a.FindChannel("B.G"), *b.FindChannel("B.G")) << "frame " << f;
            float lit = 0;
            for (float v : *a.FindChannel("R")) lit += v;
            EXPECT_GT(lit, 0) << "frame " << f << ": the light reaches the camera";
        }
    }
}

TEST_F(ShotWorkerTest, WithoutAnimationEveryFrameIsTheStill) {
    const BlobRef scene =
        Put("cornell_box.json", ReadText(fs::path(LF_TEST_SCENES) / "cornell_box.json"));
    const JobRecord still = Render(Spec(scene, std::nullopt));
    ASSERT_EQ(still.state, JobState::kSucceeded) << still.error;
    const JobRecord shot = Render(Spec(scene, FrameRange{5, 7, 2}, 2));
    ASSERT_EQ(shot.state, JobState::kSucceeded) << shot.error;
    const Image expected = FrameOf(still, std::nullopt);
    for (int f : {5, 7}) {
        EXPECT_EQ(*FrameOf(shot, f).FindChannel("R"), *expected.FindChannel("R")) << f;
        EXPECT_EQ(*FrameOf(shot, f).FindChannel("B.B"), *expected.FindChannel("B.B")) << f;
    }
}

}  // namespace
}  // namespace lf
