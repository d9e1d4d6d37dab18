// The farm end to end on loopback: the real lightfarm-server, lightfarm-worker and lightfarm
// binaries, ports chosen by the OS. Farm renders must equal `lightfarm render` bit for bit,
// whatever the workers, tiles, passes, or a worker killed halfway. Every wait is bounded and
// every child is killed in TearDown.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cutting_proxy.h"
#include "gltf_files.h"
#include "image_files.h"
#include "lf/core/image_io.h"
#include "lf/job/digest.h"
#include "test_dir.h"
#include "vdb_files.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// How long a test waits for a worker to stop a task it was told to stop (normally a heartbeat's
// 300 ms): far above that, so that a loaded machine does not fail the test, and far below the
// minutes the stopped work would have taken.
constexpr milliseconds kStopWithin{20000};

// A child process whose stderr goes to a log file and whose stdout is read through a pipe.
class Child {
  public:
    Child(const std::vector<std::string>& argv, const std::string& log) {
        int out[2];
        if (pipe(out) != 0) return;
        pid_ = fork();
        if (pid_ == 0) {
            dup2(out[1], STDOUT_FILENO);
            const int err = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            dup2(err, STDERR_FILENO);
            close(out[0]);
            std::vector<char*> args;
            for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
            args.push_back(nullptr);
            execv(args[0], args.data());
            _exit(127);
        }
        close(out[1]);
        stdout_ = out[0];
    }
    ~Child() {
        Signal(SIGKILL);
        Wait(milliseconds(5000));
        if (stdout_ >= 0) close(stdout_);
    }
    Child(const Child&) = delete;
    Child& operator=(const Child&) = delete;

    pid_t pid() const { return pid_; }
    void Signal(int sig) {
        if (pid_ > 0 && !exit_status_) kill(pid_, sig);
    }
    // The first line of stdout, or "" after `timeout`.
    std::string ReadLine(milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        std::string line;
        while (Clock::now() < deadline) {
            pollfd p{stdout_, POLLIN, 0};
            const int left =
                int(std::chrono::duration_cast<milliseconds>(deadline - Clock::now()).count());
            if (poll(&p, 1, std::max(left, 1)) <= 0) continue;
            char c;
            if (read(stdout_, &c, 1) != 1) break;
            if (c == '\n') return line;
            line.push_back(c);
        }
        return "";
    }
    // The exit status, or nullopt when the child is still running after `timeout`.
    std::optional<int> Wait(milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        while (pid_ > 0 && !exit_status_) {
            int status = 0;
            if (waitpid(pid_, &status, WNOHANG) == pid_) {
                exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            } else if (Clock::now() > deadline) {
                break;
            } else {
                std::this_thread::sleep_for(milliseconds(10));
            }
        }
        return exit_status_;
    }

  private:
    pid_t pid_ = -1;
    int stdout_ = -1;
    std::optional<int> exit_status_;
};

struct CliRun {
    int status;
    std::string out, err;
    std::string LastLine() const {
        std::string s = out;
        while (!s.empty() && s.back() == '\n') s.pop_back();
        return s.substr(s.rfind('\n') == std::string::npos ? 0 : s.rfind('\n') + 1);
    }
};

// `BINARY ARGS` of the build's bin folder: its exit status and stdout.
std::pair<int, std::string> RunBinary(const std::string& command) {
    FILE* pipe = popen((std::string(LF_BIN_DIR) + "/" + command).c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    return {WEXITSTATUS(pclose(pipe)), out};
}

std::string ReadText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// A shot of the moving ball under a moving camera, blurred, in small frames.
std::string ShotScene() {
    return (fs::path(LF_TEST_SCENES) / "shots" / "moving_ball_camera.gltf").string();
}
constexpr const char* kShotFlags = "--resolution 96x54 --shutter 0.5 --seed 3 --method path";

std::vector<nlohmann::json> JsonLines(const std::string& out);

class Farm : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_farm");
        scene_ = WriteScene("cornell64.json", 64);
    }

    void TearDown() override {
        if (HasFailure()) {
            for (const auto& e : fs::directory_iterator(dir_)) {
                if (e.path().extension() == ".log") {
                    std::printf("---- %s\n%s", e.path().filename().c_str(),
                                ReadText(e.path()).c_str());
                }
            }
        }
        children_.clear();  // kills them
        fs::remove_all(dir_);
    }

    // The Cornell box at `resolution` squared.
    std::string WriteScene(const std::string& name, int resolution) {
        nlohmann::json scene =
            nlohmann::json::parse(ReadText(fs::path(LF_TEST_SCENES) / "cornell_box.json"));
        scene["camera"]["resolution"] = {resolution, resolution};
        std::ofstream(dir_ / name) << scene.dump(1);
        return (dir_ / name).string();
    }

    void StartServer(double lease_seconds = 10, const std::string& listen = "127.0.0.1:0",
                     const std::vector<std::string>& more_args = {}) {
        ++server_runs_;
        std::vector<std::string> argv = {std::string(LF_BIN_DIR) + "/lightfarm-server",
                                         "--listen",
                                         listen,
                                         "--data-dir",
                                         (dir_ / "data").string(),
                                         "--lease-seconds",
                                         std::to_string(lease_seconds)};
        argv.insert(argv.end(), more_args.begin(), more_args.end());
        server_ = Spawn(argv, "server-" + std::to_string(server_runs_) + ".log");
        const std::string line = server_->ReadLine(milliseconds(10000));
        ASSERT_EQ(line.rfind("listening on ", 0), 0u) << "server said: " << line;
        address_ = line.substr(std::strlen("listening on "));
    }

    Child* StartWorker(const std::string& name, int threads = 1,
                       const std::vector<std::string>& more_args = {}) {
        std::vector<std::string> argv = {std::string(LF_BIN_DIR) + "/lightfarm-worker",
                                         "--server",
                                         address_,
                                         "--threads",
                                         std::to_string(threads),
                                         "--cache-dir",
                                         (dir_ / ("cache-" + name)).string()};
        argv.insert(argv.end(), more_args.begin(), more_args.end());
        return Spawn(argv, name + ".log");
    }
    // Polls `workers` until it lists `count` workers, for at most 10 s.
    bool WaitForWorkers(size_t count) {
        for (int i = 0; i < 500; ++i) {
            if (JsonLines(Farmctl("workers --json").out).size() >= count) return true;
            std::this_thread::sleep_for(milliseconds(20));
        }
        return false;
    }

    Child* Spawn(const std::vector<std::string>& argv, const std::string& log) {
        children_.push_back(std::make_unique<Child>(argv, (dir_ / log).string()));
        return children_.back().get();
    }

    // `lightfarm ARGS`, bounded by `timeout` seconds.
    CliRun Lightfarm(const std::string& args, int timeout = 60) {
        const fs::path err = dir_ / "cli.err";
        const std::string cmd = "timeout " + std::to_string(timeout) + " " +
                                std::string(LF_BIN_DIR) + "/lightfarm " + args + " 2>" +
                                err.string();
        FILE* pipe = popen(cmd.c_str(), "r");
        std::string out;
        char buf[4096];
        while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
        const int status = pclose(pipe);
        return {WEXITSTATUS(status), out, ReadText(err)};
    }
    CliRun Farmctl(const std::string& args, int timeout = 60) {
        return Lightfarm(args + " --server " + address_, timeout);
    }

    std::string Submit(const std::string& scene, const std::string& settings) {
        const CliRun r = Farmctl("submit " + scene + " " + settings);
        EXPECT_EQ(r.status, 0) << r.out << r.err;
        return r.LastLine();
    }

    // Kills the server without warning and starts it again on the same port and data.
    void CrashAndRestartServer() {
        server_->Signal(SIGKILL);
        ASSERT_TRUE(server_->Wait(milliseconds(5000)));
        const std::string address = address_;
        StartServer(10, address);
        ASSERT_EQ(address_, address);
    }

    struct TaskCounts {
        int done = -1, total = -1, running = -1, retried = -1, leased = -1;
    };
    TaskCounts Tasks(const std::string& job) {
        const std::string out = Farmctl("status " + job).out;
        TaskCounts c;
        const size_t at = out.find("tasks ");
        if (at != std::string::npos) {
            std::sscanf(out.c_str() + at, "tasks %d/%d done, %d running, %d retried, %d leased",
                        &c.done, &c.total, &c.running, &c.retried, &c.leased);
        }
        return c;
    }
    // Polls until at least `done` tasks of the job are done, for at most `timeout`.
    bool WaitForTasksDone(const std::string& job, int done, milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        while (Clock::now() < deadline) {
            if (Tasks(job).done >= done) return true;
            std::this_thread::sleep_for(milliseconds(20));
        }
        return false;
    }

    // Polls `status` until `pattern` shows up, for at most `timeout`.
    bool WaitForStatus(const std::string& job, const std::string& pattern, milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        while (Clock::now() < deadline) {
            if (Farmctl("status " + job).out.find(pattern) != std::string::npos) return true;
            std::this_thread::sleep_for(milliseconds(20));
        }
        return false;
    }

    // Kills `worker` while it holds a lease, so that its task must be leased again: stopped
    // (SIGSTOP) at a moment when its log shows a task leased and not yet ended, then killed.
    // Whatever the machine's load does to the spacing of its tasks, the kill is mid-task.
    bool KillMidTask(Child* worker, const std::string& log) {
        const auto count = [](const std::string& text, const std::string& what) {
            int n = 0;
            for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
                ++n;
            return n;
        };
        const auto deadline = Clock::now() + milliseconds(20000);
        while (Clock::now() < deadline) {
            worker->Signal(SIGSTOP);
            while (!IsStopped(worker->pid())) std::this_thread::sleep_for(milliseconds(1));
            const std::string text = ReadText(dir_ / log);
            const int ended = count(text, " rendered in ") + count(text, " failed after ") +
                              count(text, " dropped: ") + count(text, " handed back: ");
            if (count(text, " leased: ") > ended) {
                worker->Signal(SIGKILL);
                return true;
            }
            worker->Signal(SIGCONT);
            std::this_thread::sleep_for(milliseconds(5));
        }
        return false;
    }
    // Not running, nor able to run: /proc/PID/stat is "PID (NAME) STATE ...", and STATE is T
    // once a SIGSTOP took effect (Z or no file: it is gone).
    static bool IsStopped(pid_t pid) {
        const std::string stat = ReadText("/proc/" + std::to_string(pid) + "/stat");
        const size_t paren = stat.rfind(')');
        if (paren == std::string::npos || paren + 2 >= stat.size()) return true;
        return std::string_view("RSD").find(stat[paren + 2]) == std::string_view::npos;
    }

    // Polls the file at `path` until `text` shows up, for at most `timeout`.
    bool WaitForText(const fs::path& path, const std::string& text, milliseconds timeout) {
        const auto deadline = Clock::now() + timeout;
        while (Clock::now() < deadline) {
            if (ReadText(path).find(text) != std::string::npos) return true;
            std::this_thread::sleep_for(milliseconds(5));
        }
        return false;
    }

    // Watches the job to its end, fetches it, and compares every sample channel with a local
    // render of the same scene and settings.
    void ExpectSameAsLocal(const std::string& job, const std::string& scene, uint64_t spp,
                           uint64_t seed, const std::string& method_flags = "--method path") {
        const CliRun watch = Farmctl("watch " + job);
        ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
        const std::string farm = (dir_ / (job + ".exr")).string();
        const CliRun fetch = Farmctl("fetch " + job + " -o " + farm);
        ASSERT_EQ(fetch.status, 0) << fetch.out << fetch.err;

        const std::string local =
            (dir_ / ("local-" + std::to_string(spp) + "-" + std::to_string(seed) + "-" +
                     std::to_string(std::hash<std::string>{}(method_flags)) + ".exr"))
                .string();
        if (!fs::exists(local)) {
            const CliRun r = Lightfarm("render " + scene + " -o " + local + " --spp " +
                                       std::to_string(spp) + " --seed " + std::to_string(seed) +
                                       " " + method_flags + " --threads 2 --no-progress");
            ASSERT_EQ(r.status, 0) << r.out << r.err;
        }
        ExpectSameImageAndHeader(farm, local);
    }

    // Every channel bit for bit, and the same header attributes with the same values but for
    // the timings, which no two runs share.
    void ExpectSameImageAndHeader(const std::string& farm, const std::string& local) {
        absl::StatusOr<ExrFile> a = ReadExr(farm), b = ReadExr(local);
        ASSERT_TRUE(a.ok()) << a.status();
        ASSERT_TRUE(b.ok()) << b.status();
        // Every channel: the sample channels and any AOVs (albedo.R, ..., depth.Z).
        for (const char* ch : {"R", "G", "B", "A.R", "A.G", "A.B", "B.R", "B.G", "B.B", "spp"}) {
            ASSERT_TRUE(a->image.FindChannel(ch)) << ch;
        }
        ASSERT_EQ(a->image.channels().size(), b->image.channels().size());
        for (const auto& [ch, x] : a->image.channels()) {
            const std::vector<float>* y = b->image.FindChannel(ch);
            ASSERT_TRUE(y) << ch << " is not in the local render";
            ASSERT_EQ(x.size(), y->size()) << ch;
            EXPECT_EQ(0, std::memcmp(x.data(), y->data(), x.size() * sizeof(float)))
                << "channel " << ch << " differs from the local render";
        }
        // Costs of the process that rendered: times, and hierarchical radiosity's memory (the
        // farm's is the sum over its chunks, each holding the cluster tree).
        const std::set<std::string> timings = {
            "lightfarm.seconds", "lightfarm.radiosity.formFactorSeconds",
            "lightfarm.radiosity.solveSeconds", "lightfarm.radiosity.linkBytes",
            "lightfarm.radiosity.solverBytes"};
        std::set<std::string> farm_names, local_names;
        for (const auto& [name, value] : a->attributes) {
            if (name.rfind("lightfarm.", 0) == 0) farm_names.insert(name);
        }
        for (const auto& [name, value] : b->attributes) {
            if (name.rfind("lightfarm.", 0) == 0) local_names.insert(name);
        }
        EXPECT_EQ(farm_names, local_names);
        for (const std::string& name : farm_names) {
            if (timings.count(name) || !b->attributes.count(name)) continue;
            EXPECT_EQ(a->attributes.at(name), b->attributes.at(name)) << name;
        }
        EXPECT_TRUE(a->attributes.count("lightfarm.seconds"));
    }

    // Every frame of `frames` fetched from the farm equals `lightfarm render --frames RANGE
    // FLAGS`, bit for bit and header for header (lightfarm.frame, .time, .fps, .shutter
    // included).
    void ExpectFramesAsRendered(const std::string& job, const std::vector<int>& frames,
                                const std::string& range, const std::string& flags) {
        const std::string farm = (dir_ / "farm_####.exr").string();
        const CliRun fetch = Farmctl("fetch " + job + " --frames " + range + " -o " + farm);
        ASSERT_EQ(fetch.status, 0) << fetch.out << fetch.err;
        const std::string local = (dir_ / "local_####.exr").string();
        const CliRun r = Lightfarm("render " + ShotScene() + " --frames " + range + " " + flags +
                                   " -o " + local + " --threads 2 --no-progress");
        ASSERT_EQ(r.status, 0) << r.out << r.err;
        for (int f : frames) {
            char name[32];
            std::snprintf(name, sizeof name, "_%04d.exr", f);
            SCOPED_TRACE(::testing::Message() << "frame " << f);
            ExpectSameImageAndHeader((dir_ / ("farm" + std::string(name))).string(),
                                     (dir_ / ("local" + std::string(name))).string());
        }
    }

    fs::path dir_;
    std::string scene_;
    std::string address_;
    int server_runs_ = 0;
    Child* server_ = nullptr;
    std::vector<std::unique_ptr<Child>> children_;
};

TEST_F(Farm, HelpExplainsEveryFarmCommand) {
    for (const char* cmd : {"submit", "list", "status", "watch", "fetch", "cancel", "delete",
                            "tasks", "logs", "stats", "depend"}) {
        const CliRun r = Lightfarm(std::string(cmd) + " --help");
        EXPECT_EQ(r.status, 0) << cmd;
        EXPECT_NE(r.out.find("--server"), std::string::npos) << cmd << r.out;
    }
    for (auto [binary, option] : {std::pair{"lightfarm-server", "--data-dir"},
                                  std::pair{"lightfarm-worker", "--cache-dir"}}) {
        const auto [status, out] = RunBinary(std::string(binary) + " --help");
        EXPECT_EQ(status, 0) << binary;
        EXPECT_NE(out.find(option), std::string::npos) << out;
    }
}

// `--json` on list, status and workers: one object a line, with the wire message's field names,
// that a script can parse and that agrees with the table.
TEST_F(Farm, ListStatusAndWorkersPrintOneJsonObjectALine) {
    StartServer();
    Spawn({std::string(LF_BIN_DIR) + "/lightfarm-worker", "--server", address_, "--threads", "1",
           "--name", "node \"7\"", "--cache-dir", (dir_ / "cache-json").string()},
          "w-json.log");
    const std::string first = Submit(scene_, "--spp 2 --tile 32 --name first");
    const std::string second = Submit(scene_, "--spp 2 --tile 32 --name second");
    ASSERT_EQ(Farmctl("watch " + second).status, 0);
    ASSERT_EQ(Farmctl("watch " + first).status, 0);

    const CliRun list = Farmctl("list --json");
    ASSERT_EQ(list.status, 0) << list.err;
    std::vector<nlohmann::json> jobs;
    std::istringstream lines(list.out);
    for (std::string line; std::getline(lines, line);) jobs.push_back(nlohmann::json::parse(line));
    ASSERT_EQ(jobs.size(), 2u) << list.out;
    EXPECT_EQ(jobs[0]["id"], second);  // newest first, as the table
    EXPECT_EQ(jobs[1]["id"], first);
    EXPECT_EQ(jobs[1]["name"], "first");
    EXPECT_EQ(jobs[1]["state"], "SUCCEEDED");
    EXPECT_EQ(jobs[1]["tasks_done"], jobs[1]["tasks_total"]);
    EXPECT_EQ(jobs[1]["params"]["spp"], "2");  // 64-bit integers are strings in protobuf's JSON

    const CliRun status = Farmctl("status --json " + first);
    ASSERT_EQ(status.status, 0) << status.err;
    EXPECT_EQ(nlohmann::json::parse(status.out), jobs[1]);

    const CliRun workers = Farmctl("workers --json");
    ASSERT_EQ(workers.status, 0) << workers.err;
    const nlohmann::json worker = nlohmann::json::parse(workers.out);
    EXPECT_EQ(worker["name"], "node \"7\"");  // escaped, and read back as it was given
    EXPECT_EQ(worker["state"], "IDLE");
    EXPECT_FALSE(worker["version"].get<std::string>().empty());
}

std::vector<nlohmann::json> JsonLines(const std::string& out) {
    std::vector<nlohmann::json> objects;
    std::istringstream lines(out);
    for (std::string line; std::getline(lines, line);) {
        objects.push_back(nlohmann::json::parse(line));
    }
    return objects;
}

// The first column of each line of a table after its header.
std::vector<std::string> FirstColumn(const std::string& table) {
    std::vector<std::string> column;
    std::istringstream lines(table);
    std::string line;
    std::getline(lines, line);
    while (std::getline(lines, line)) column.push_back(line.substr(0, line.find(' ')));
    return column;
}

// `submit --watch` prints the job's id first (a script reads it while the job runs), then
// follows the job to its end as `watch` does, with watch's exit status.
TEST_F(Farm, SubmitWithWatchPrintsTheIdThenFollowsTheJobToItsEnd) {
    StartServer();
    StartWorker("w1");
    const CliRun done = Farmctl("submit " + scene_ + " --spp 2 --tile 16 --watch");
    ASSERT_EQ(done.status, 0) << done.out << done.err;
    const std::string id = done.out.substr(0, done.out.find('\n'));
    ASSERT_EQ(id.rfind("job-", 0), 0u) << done.out;
    EXPECT_EQ(done.LastLine().rfind("job " + id + " succeeded (", 0), 0u) << done.out;

    // Without a free worker the job waits: cancelled meanwhile, it ends the command with 1.
    Child* waiting = Spawn({std::string(LF_BIN_DIR) + "/lightfarm", "submit", scene_, "--spp", "2",
                            "--tags", "gpu", "--watch", "--server", address_},
                           "submit-watch.log");
    const std::string queued = waiting->ReadLine(milliseconds(20000));
    ASSERT_EQ(queued.rfind("job-", 0), 0u) << queued;
    ASSERT_EQ(Farmctl("cancel " + queued).status, 0);
    EXPECT_EQ(waiting->Wait(milliseconds(20000)), std::optional<int>(1))
        << ReadText(dir_ / "submit-watch.log");
    const std::string ended = waiting->ReadLine(milliseconds(5000));
    EXPECT_EQ(ended.rfind("job " + queued + " cancelled", 0), 0u) << ended;
}

// Issue 27: two workers on one host both showed as the host name in `workers`, while `tasks`
// named them by id. Both tables name a worker by the one identity the server knows it by.
TEST_F(Farm, WorkersAndTasksNameTwoWorkersOfOneHostAlike) {
    StartServer();
    StartWorker("w1");  // no --name: both are named after this host
    StartWorker("w2");
    const std::string job = Submit(scene_, "--spp 2 --tile 16");
    ASSERT_EQ(Farmctl("watch " + job).status, 0);
    std::vector<nlohmann::json> listed;
    for (int i = 0; i < 500 && listed.size() < 2; ++i) {
        listed = JsonLines(Farmctl("workers --json").out);
        std::this_thread::sleep_for(milliseconds(20));
    }
    ASSERT_EQ(listed.size(), 2u);
    EXPECT_EQ(listed[0]["name"], listed[1]["name"]);
    EXPECT_NE(listed[0]["id"], listed[1]["id"]);

    const CliRun workers = Farmctl("workers");
    ASSERT_EQ(workers.status, 0) << workers.err;
    std::vector<std::string> shown = FirstColumn(workers.out);
    std::sort(shown.begin(), shown.end());
    std::vector<std::string> ids = {listed[0]["id"], listed[1]["id"]};
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(shown, ids) << workers.out;

    const CliRun table = Farmctl("tasks " + job);
    ASSERT_EQ(table.status, 0) << table.err;
    const std::vector<nlohmann::json> tasks = JsonLines(Farmctl("tasks --json " + job).out);
    ASSERT_FALSE(tasks.empty());
    for (const nlohmann::json& task : tasks) {
        const std::string worker = task["worker"];
        EXPECT_NE(std::find(ids.begin(), ids.end(), worker), ids.end()) << worker;
        EXPECT_NE(table.out.find(" " + worker + " "), std::string::npos) << table.out;
    }
}

// `lightfarm logs` prints what the worker logged during each task, one task's with --task, as
// JSON with --json; `lightfarm tasks` lists them. A task failing on its worker (its scene's
// blob gone from the server) fails the job naming the task and its error, and --follow prints
// the error lines until the job ends.
// Pools and worker control (issue 30): a job tagged gpu renders on the gpu worker alone; a
// disabled worker stays disabled across a server restart, and the other renders everything.
TEST_F(Farm, TaggedJobGoesToTheTaggedWorkerAndDisableSurvivesARestart) {
    StartServer();
    StartWorker("cpu", 1, {"--name", "cpu"});
    StartWorker("gpu", 1, {"--name", "gpu", "--tags", "gpu,linux"});
    // The worker of each name, once both are listed.
    const auto ids = [&] {
        std::map<std::string, std::string> by_name;
        for (int i = 0; i < 500 && by_name.size() < 2; ++i) {
            by_name.clear();
            for (const nlohmann::json& w : JsonLines(Farmctl("workers --json").out)) {
                if (w.value("state", "") != "OFFLINE") by_name[w["name"]] = w["id"];
            }
            std::this_thread::sleep_for(milliseconds(20));
        }
        return by_name;
    };
    std::map<std::string, std::string> workers = ids();
    ASSERT_EQ(workers.size(), 2u);
    const CliRun table = Farmctl("workers");
    EXPECT_NE(table.out.find(" gpu,linux "), std::string::npos) << table.out;

    const std::string tagged = Submit(scene_, "--spp 2 --tile 16 --tags gpu --max-workers 1");
    ASSERT_EQ(Farmctl("watch " + tagged).status, 0);
    for (const nlohmann::json& task : JsonLines(Farmctl("tasks --json " + tagged).out)) {
        EXPECT_EQ(task["worker"], workers["gpu"]);
    }
    const CliRun status = Farmctl("status " + tagged);
    EXPECT_NE(status.out.find("workers   tags gpu, at most 1"), std::string::npos) << status.out;

    const CliRun disable = Farmctl("workers disable gpu");
    ASSERT_EQ(disable.status, 0) << disable.err;
    EXPECT_NE(disable.out.find("disabled"), std::string::npos) << disable.out;
    server_->Signal(SIGTERM);
    ASSERT_EQ(server_->Wait(milliseconds(5000)), std::optional<int>(0));
    const std::string address = address_;
    StartServer(10, address);
    ASSERT_EQ(address_, address);
    workers = ids();
    ASSERT_EQ(workers.size(), 2u);
    for (const nlohmann::json& w : JsonLines(Farmctl("workers --json").out)) {
        if (w["name"] == "gpu") {
            EXPECT_EQ(w["state"], "DISABLED") << w.dump();
        }
    }
    const std::string plain = Submit(scene_, "--spp 2 --tile 16");
    ASSERT_EQ(Farmctl("watch " + plain).status, 0);
    for (const nlohmann::json& task : JsonLines(Farmctl("tasks --json " + plain).out)) {
        EXPECT_EQ(task["worker"], workers["cpu"]) << "the disabled worker takes nothing";
    }
    EXPECT_EQ(Farmctl("workers enable gpu").status, 0);
    EXPECT_NE(Farmctl("workers disable nobody").err.find("no worker named nobody"),
              std::string::npos);
}

// History (issue 30): a real worker's CPU and render seconds per task, summed in `stats` per
// owner and per worker, the same after a coordinator restart and after the job is deleted.
TEST_F(Farm, StatsCountARealWorkersTimesAcrossARestartAndADeletion) {
    StartServer();
    StartWorker("w1", 2);
    const auto start = Clock::now();
    const std::string job = Submit(scene_, "--spp 4 --tile 32");  // 4 tasks
    ASSERT_EQ(Farmctl("watch " + job).status, 0);
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();

    const std::vector<nlohmann::json> tasks = JsonLines(Farmctl("tasks --json " + job).out);
    ASSERT_EQ(tasks.size(), 4u);
    const double cores = std::max(1u, std::thread::hardware_concurrency());
    double cpu = 0, render = 0;
    for (const nlohmann::json& t : tasks) {
        const double task_cpu = t["cpu_seconds"], task_render = t["render_seconds"];
        EXPECT_GT(task_cpu, 0) << t;
        EXPECT_GT(task_render, 0) << t;
        // The process' CPU time over the task: at most every core for its whole render.
        EXPECT_LE(task_cpu, cores * task_render + 0.05) << t;
        cpu += task_cpu;
        render += task_render;
    }
    EXPECT_LE(render, wall);
    EXPECT_NE(Farmctl("status " + job).out.find("  worked    "), std::string::npos);

    const auto stats = [&] {
        const CliRun r = Farmctl("stats --json");
        EXPECT_EQ(r.status, 0) << r.err;
        const std::vector<nlohmann::json> lines = JsonLines(r.out);
        return lines.size() == 1 ? lines[0] : nlohmann::json();
    };
    const nlohmann::json before = stats();
    ASSERT_EQ(before["owners"].size(), 1u) << before;
    const nlohmann::json& owner = before["owners"][0];
    EXPECT_EQ(owner["owner"], "");            // authentication off
    EXPECT_EQ(owner["jobs_succeeded"], "1");  // int64s are strings in protobuf's JSON
    EXPECT_EQ(owner["jobs_active"], "0");
    EXPECT_EQ(owner["tasks"], "4");
    EXPECT_EQ(owner["samples"], std::to_string(64 * 64 * 4));
    EXPECT_NEAR(owner["cpu_seconds"].get<double>(), cpu, 1e-6 * cpu);
    EXPECT_NEAR(owner["render_seconds"].get<double>(), render, 1e-6 * render);
    ASSERT_EQ(before["workers"].size(), 1u) << before;
    EXPECT_EQ(before["workers"][0]["tasks"], "4");
    EXPECT_EQ(before["workers"][0]["worker"], tasks[0]["worker"]);

    CrashAndRestartServer();
    EXPECT_EQ(stats(), before);
    ASSERT_EQ(Farmctl("delete " + job).status, 0);
    EXPECT_EQ(stats(), before);

    const CliRun table = Farmctl("stats --since 1h");
    ASSERT_EQ(table.status, 0) << table.err;
    EXPECT_NE(table.out.find("OWNER  SUCCEEDED  FAILED  CANCELLED  ACTIVE  TASKS"),
              std::string::npos)
        << table.out;
    EXPECT_NE(table.out.find("WORKER"), std::string::npos) << table.out;
    for (const char* bad : {"--since 2999-01-01", "--since soon", "--since 0d"}) {
        const CliRun r = Farmctl(std::string("stats ") + bad);
        EXPECT_NE(r.status, 0) << bad;
        EXPECT_NE(r.err.find("--since "), std::string::npos) << r.err;
        EXPECT_TRUE(r.out.empty()) << r.out;
    }
}

TEST_F(Farm, LogsAndTasksShowWhatEachTaskDidAndWhyOneFailed) {
    StartServer();
    Child* worker = StartWorker("w1");
    const std::string job = Submit(scene_, "--spp 2 --tile 32");  // 4 tasks
    ASSERT_EQ(Farmctl("watch " + job).status, 0);

    const CliRun logs = Farmctl("logs " + job);
    ASSERT_EQ(logs.status, 0) << logs.err;
    for (int t = 0; t < 4; ++t) {
        const std::string ids = " task " + std::to_string(t) + " #1 ";
        EXPECT_NE(logs.out.find(ids), std::string::npos) << logs.out;
        EXPECT_NE(logs.out.find("task=" + std::to_string(t) + " leased: path, pixels"),
                  std::string::npos)
            << logs.out;
    }
    EXPECT_NE(logs.out.find("rendered in"), std::string::npos) << logs.out;

    const CliRun one = Farmctl("logs " + job + " --task 2");
    ASSERT_EQ(one.status, 0) << one.err;
    std::istringstream lines(one.out);
    int count = 0;
    for (std::string line; std::getline(lines, line); ++count) {
        EXPECT_NE(line.find(" task 2 #1 "), std::string::npos) << line;
    }
    EXPECT_GE(count, 3) << one.out;  // leased, scene, rendered

    const std::vector<nlohmann::json> json = JsonLines(Farmctl("logs --json " + job).out);
    ASSERT_FALSE(json.empty());
    std::set<int> tasks_logged;
    for (const nlohmann::json& line : json) {
        tasks_logged.insert(line["task_index"].get<int>());
        EXPECT_EQ(line["attempt"], 1);
        EXPECT_EQ(line["level"], "info");
        EXPECT_FALSE(line["worker"].get<std::string>().empty());
    }
    EXPECT_EQ(tasks_logged, (std::set<int>{0, 1, 2, 3}));

    const std::vector<nlohmann::json> tasks = JsonLines(Farmctl("tasks --json " + job).out);
    ASSERT_EQ(tasks.size(), 4u);
    for (const nlohmann::json& task : tasks) {
        EXPECT_EQ(task["state"], "DONE");
        EXPECT_EQ(task["kind"], "TILE");
        EXPECT_EQ(task["width"], 32);
        EXPECT_EQ(task["attempts"], 1);
        EXPECT_GE(task["log_lines"].get<int>(), 3);
    }

    // A new worker with an empty cache, for a job whose blob the server lost: each lease fails.
    worker->Signal(SIGTERM);
    ASSERT_TRUE(worker->Wait(milliseconds(10000)));
    const std::string failing = Submit(WriteScene("cornell32.json", 32), "--spp 2 --tile 32");
    for (const auto& e : fs::directory_iterator(dir_ / "data" / "blobs")) {
        if (e.is_regular_file()) fs::remove(e.path());
    }
    StartWorker("w2");
    const CliRun follow = Farmctl("logs --follow " + failing);
    ASSERT_EQ(follow.status, 0) << follow.err;
    EXPECT_NE(follow.out.find(" task 0 #3 "), std::string::npos) << follow.out;
    EXPECT_NE(follow.out.find("error"), std::string::npos) << follow.out;
    EXPECT_NE(follow.out.find("task=0 failed after"), std::string::npos) << follow.out;
    EXPECT_NE(follow.out.find("no blob"), std::string::npos) << follow.out;

    const CliRun status = Farmctl("status " + failing);
    EXPECT_NE(status.out.find("failed"), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("error     task 0 failed 3 times; last: no blob"), std::string::npos)
        << status.out;
    EXPECT_NE(status.out.find("last error  task 0: no blob"), std::string::npos) << status.out;
    const std::vector<nlohmann::json> failed = JsonLines(Farmctl("tasks --json " + failing).out);
    ASSERT_EQ(failed.size(), 1u);
    EXPECT_EQ(failed[0]["state"], "DROPPED");
    EXPECT_EQ(failed[0]["failures"], 3);
    EXPECT_NE(failed[0]["last_error"].get<std::string>().find("no blob"), std::string::npos);

    // An ended job's tasks and logs outlive the server; they go with the job.
    CrashAndRestartServer();
    EXPECT_EQ(JsonLines(Farmctl("tasks --json " + job).out).size(), 4u);
    EXPECT_EQ(JsonLines(Farmctl("logs --json " + job).out).size(), json.size());
    ASSERT_EQ(Farmctl("delete " + job).status, 0);
    const CliRun gone = Farmctl("logs " + job);
    EXPECT_NE(gone.status, 0);
    EXPECT_NE(gone.err.find("no job " + job), std::string::npos) << gone.err;
}

TEST_F(Farm, SameBitsAsLocalRenderForAnyWorkersAndTiles) {
    StartServer();
    StartWorker("w1");
    for (int workers : {1, 2}) {
        if (workers == 2) StartWorker("w2");
        for (const char* tile : {"16", "24"}) {
            const std::string job =
                Submit(scene_, std::string("--spp 8 --seed 5 --passes 2 --tile ") + tile);
            ExpectSameAsLocal(job, scene_, 8, 5);
        }
    }
}

// AOVs, a wide filter and a clamp on two workers, in tiles and passes unlike the local render's:
// every channel has the local bits, also after the server was killed mid-render and rebuilt its
// tiles (AOV sums included, illuminance's too) from the results its job store kept.
TEST_F(Farm, AovsFilterAndClampGiveTheLocalBitsForAnyTilesAndAcrossARestart) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string filter_and_clamp = " --filter gaussian:3 --clamp 2";
    for (const char* tile : {"8", "24"}) {
        const std::string extras = "--aov all" + filter_and_clamp;
        const std::string job = Submit(
            scene_, std::string("--spp 8 --seed 5 --passes 2 --tile ") + tile + " " + extras);
        ExpectSameAsLocal(job, scene_, 8, 5, "--method path " + extras);
    }
    // Illuminance too: its sums survive the restart in the job store and the tile store.
    const std::string extras = "--aov albedo,depth,illuminance" + filter_and_clamp;
    const std::string job = Submit(scene_, "--spp 256 --seed 6 --tile 16 --passes 2 " + extras);
    ASSERT_TRUE(WaitForTasksDone(job, 8, milliseconds(30000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 256, 6, "--method path " + extras);
}

TEST_F(Farm, KilledWorkerDoesNotChangeTheImage) {
    StartServer(/*lease_seconds=*/1);
    Child* doomed = StartWorker("doomed");
    StartWorker("survivor");
    const std::string job = Submit(scene_, "--spp 512 --seed 9 --tile 32 --passes 2");
    ASSERT_TRUE(KillMidTask(doomed, "doomed.log"));
    ExpectSameAsLocal(job, scene_, 512, 9);
    // Its task went to the survivor: retried after the lease expired, or leased again
    // speculatively before that.
    const TaskCounts c = Tasks(job);
    EXPECT_GT(c.leased, c.total) << "no task was leased again";
}

TEST_F(Farm, CancelStopsTheWork) {
    StartServer();
    StartWorker("w1");
    // One task that would take minutes.
    const std::string job = Submit(scene_, "--spp 65536 --tile 64");
    ASSERT_TRUE(WaitForStatus(job, "1 running", milliseconds(20000)));
    const std::string preview = (dir_ / "preview.exr").string();
    const CliRun not_yet = Farmctl("fetch " + job + " -o " + preview);
    EXPECT_NE(not_yet.status, 0);
    EXPECT_NE(not_yet.err.find("no result yet"), std::string::npos) << not_yet.err;
    const CliRun fetch_preview = Farmctl("fetch --preview " + job + " -o " + preview);
    ASSERT_EQ(fetch_preview.status, 0) << fetch_preview.err;
    absl::StatusOr<ExrFile> partial = ReadExr(preview);
    ASSERT_TRUE(partial.ok()) << partial.status();
    EXPECT_EQ(partial->image.width(), 64);
    EXPECT_EQ((*partial->image.FindChannel("spp"))[0], 0.0f);  // nothing merged yet

    const CliRun cancel = Farmctl("cancel " + job);
    ASSERT_EQ(cancel.status, 0) << cancel.out << cancel.err;
    EXPECT_NE(cancel.out.find("cancelled"), std::string::npos) << cancel.out;
    // The worker drops the task (it says so once its render has returned) long before the
    // task could have been rendered, and never reports it rendered.
    EXPECT_TRUE(WaitForText(dir_ / "w1.log", "job=" + job + " task=0 dropped", kStopWithin))
        << "the worker still renders after the cancel";

    // The worker is free again: a small job right after it finishes.
    const std::string next = Submit(scene_, "--spp 4 --tile 32");
    const CliRun watch = Farmctl("watch " + next, 20);
    EXPECT_EQ(watch.status, 0) << watch.out << watch.err;

    const CliRun watch_cancelled = Farmctl("watch " + job);
    EXPECT_EQ(watch_cancelled.status, 1);
    EXPECT_NE(watch_cancelled.out.find("cancelled"), std::string::npos) << watch_cancelled.out;
    EXPECT_NE(Farmctl("cancel " + job).status, 0);  // already ended
    EXPECT_EQ(ReadText(dir_ / "w1.log").find("job=" + job + " task=0 rendered"), std::string::npos);
}

// Form factors are the long part of a radiosity task: a cancel stops them too.
TEST_F(Farm, CancelStopsARadiositySolve) {
    StartServer();
    StartWorker("w1");
    // One chunk of form factors for 12k patches: half a minute on one thread.
    const std::string job =
        Submit(scene_, "--method radiosity --solver jacobi --patches 12000 --sweep-tasks 1");
    ASSERT_TRUE(WaitForStatus(job, "1 running", milliseconds(20000)));
    // The scene is loaded, so the form factors are under way.
    ASSERT_TRUE(WaitForText(dir_ / "w1.log", "loaded", milliseconds(20000)));
    ASSERT_EQ(Farmctl("cancel " + job).status, 0);
    // The job's only task so far (its number depends on the plan).
    EXPECT_TRUE(WaitForText(dir_ / "w1.log", "dropped: the job was cancelled", kStopWithin))
        << "the worker still computes after the cancel";
    const CliRun watch = Farmctl("watch " + Submit(scene_, "--spp 4 --tile 32"), 20);
    EXPECT_EQ(watch.status, 0) << watch.out << watch.err;
    // It stopped in the form factors: the worker never logged them done.
    EXPECT_EQ(ReadText(dir_ / "w1.log").find("form factors of chunk"), std::string::npos);
}

TEST_F(Farm, HigherPriorityJobOvertakesAnEarlierOne) {
    StartServer();
    StartWorker("w1");
    const std::string big = WriteScene("cornell128.json", 128);
    const std::string low = Submit(big, "--spp 256 --tile 16 --passes 2 --priority 0");
    ASSERT_TRUE(WaitForStatus(low, "running", milliseconds(20000)));
    const std::string high = Submit(scene_, "--spp 8 --tile 16 --priority 10");
    const CliRun watch = Farmctl("watch " + high);
    ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
    const std::string low_status = Farmctl("status " + low).out;
    EXPECT_NE(low_status.find(": running"), std::string::npos) << low_status;
    const CliRun list = Farmctl("list");
    EXPECT_NE(list.out.find(high), std::string::npos) << list.out;
    EXPECT_LT(list.out.find(high), list.out.find(low)) << "newest first:\n" << list.out;
    // Each row says when its job was submitted, as a local date and time.
    EXPECT_TRUE(
        std::regex_search(list.out, std::regex(high + R"(.* \d{4}-\d\d-\d\d \d\d:\d\d:\d\d )")))
        << list.out;
    Farmctl("cancel " + low);
}

TEST_F(Farm, MalformedSceneIsRefusedAndTheServerStaysUp) {
    StartServer();
    StartWorker("w1");
    std::ofstream(dir_ / "bad.json") << "{\n  \"camera\": {\n    \"position\": [0, 0,\n";
    const CliRun bad = Farmctl("submit " + (dir_ / "bad.json").string());
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("bad.json"), std::string::npos) << bad.err;
    EXPECT_EQ(bad.err.find("not reachable"), std::string::npos) << bad.err;

    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["shapes"][0]["material"] = "no_such_material";
    std::ofstream(dir_ / "wrong.json") << scene.dump(1);
    const CliRun wrong = Farmctl("submit " + (dir_ / "wrong.json").string());
    EXPECT_NE(wrong.status, 0);
    EXPECT_NE(wrong.err.find("no_such_material"), std::string::npos) << wrong.err;

    const std::string job = Submit(scene_, "--spp 2");
    EXPECT_EQ(Farmctl("watch " + job).status, 0);
    EXPECT_NE(Farmctl("status job-doesnotexist").err.find("job-doesnotexist"), std::string::npos);
}

// Scripts read stdout: a list that fails prints no table header there (it did, then rc 1).
TEST_F(Farm, AFailedListPrintsNothingOnStdout) {
    const CliRun r = Lightfarm("list --server 127.0.0.1:1");
    EXPECT_NE(r.status, 0);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err, "");
}

TEST_F(Farm, TerminatedWorkerHandsItsTaskBack) {
    StartServer();
    Child* worker = StartWorker("w1");
    const std::string job = Submit(scene_, "--spp 65536 --tile 64");
    ASSERT_TRUE(WaitForStatus(job, "1 running", milliseconds(20000)));
    worker->Signal(SIGTERM);
    EXPECT_EQ(worker->Wait(kStopWithin), std::optional<int>(0));
    const std::string status = Farmctl("status " + job).out;
    EXPECT_NE(status.find("0 running, 1 retried"), std::string::npos) << status;
    EXPECT_EQ(status.find("error"), std::string::npos) << status;
    EXPECT_NE(ReadText(dir_ / "w1.log").find("handed back"), std::string::npos);
    Farmctl("cancel " + job);
}

TEST_F(Farm, WorkersComeBackAfterTheServerRestarts) {
    StartServer();
    StartWorker("w1");
    EXPECT_EQ(Farmctl("watch " + Submit(scene_, "--spp 2")).status, 0);
    server_->Signal(SIGTERM);
    ASSERT_EQ(server_->Wait(milliseconds(5000)), std::optional<int>(0));
    const std::string address = address_;
    StartServer(10, address);  // the same port
    ASSERT_EQ(address_, address);
    const CliRun watch = Farmctl("watch " + Submit(scene_, "--spp 2"), 20);
    EXPECT_EQ(watch.status, 0) << watch.out << watch.err;
}

TEST_F(Farm, AcknowledgedJobsSurviveAServerKilledRightAfterSubmit) {
    StartServer();
    const std::string first = Submit(scene_, "--spp 8 --seed 3 --tile 32 --passes 2");
    const std::string second = Submit(scene_, "--spp 8 --seed 4 --tile 32");
    CrashAndRestartServer();
    StartWorker("w1");
    ExpectSameAsLocal(first, scene_, 8, 3);
    ExpectSameAsLocal(second, scene_, 8, 4);
    const std::string list = Farmctl("list").out;
    EXPECT_EQ(list.find(first), list.rfind(first)) << "listed twice:\n" << list;
    EXPECT_EQ(Tasks(first).leased, 8);
}

TEST_F(Farm, ServerKilledTwiceMidRenderRendersNoDoneTaskAgain) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    // 16 tiles x 2 passes.
    const std::string job = Submit(scene_, "--spp 512 --seed 7 --tile 16 --passes 2");
    for (int done : {8, 20}) {
        ASSERT_TRUE(WaitForTasksDone(job, done, milliseconds(30000)));
        CrashAndRestartServer();
        // A result merged but not yet synced when the server died was not acknowledged to its
        // worker either: at most one per worker may be missing.
        EXPECT_GE(Tasks(job).done, done - 2) << "an acknowledged result was lost";
    }
    ExpectSameAsLocal(job, scene_, 512, 7);
    // A worker sends one result while it renders the next task, so each crash costs each worker
    // at most two leases: the task it was rendering and the result it had not yet had taken.
    const TaskCounts c = Tasks(job);
    EXPECT_EQ(c.done, 32);
    EXPECT_LE(c.leased, 32 + 2 * 2 * 2) << "done tasks were rendered again";
}

// Kills at seeded pseudo-random moments, so they land in different phases of the job (queued,
// mid-render, the last results and the EXR write): the job still ends with the local pixels.
TEST_F(Farm, ServerKilledAtRandomMomentsLosesNothing) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string job = Submit(scene_, "--spp 256 --seed 11 --tile 16 --passes 2");
    std::mt19937 rng(2026);
    std::uniform_int_distribution<int> delay_ms(0, 700);
    for (int crash = 0; crash < 3; ++crash) {
        std::this_thread::sleep_for(milliseconds(delay_ms(rng)));
        CrashAndRestartServer();
    }
    ExpectSameAsLocal(job, scene_, 256, 11);
    EXPECT_EQ(Tasks(job).done, 32);
}

// The moment the last result is merged the server writes the EXR; a kill then must not leave a
// job that is done without an image.
TEST_F(Farm, ServerKilledAsTheLastResultArrivesStillWritesTheImage) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string job = Submit(scene_, "--spp 64 --seed 12 --tile 16 --passes 2");
    ASSERT_TRUE(WaitForTasksDone(job, 32, milliseconds(30000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 64, 12);
}

// Radiosity on the farm: each worker solves the same system to the same bits, then renders its
// display tiles, so the image is that of `lightfarm render --method radiosity`.
TEST_F(Farm, RadiosityJobGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags = "--method radiosity --patches 300 --solver shooting";
    const std::string job = Submit(scene_, "--spp 2 --seed 6 --tile 16 " + flags);
    ExpectSameAsLocal(job, scene_, 2, 6, flags);
}

// With --solver jacobi the farm solves: sweep 0 is --sweep-tasks patch-group tasks, each chunk
// of form-factor rows is computed once, by the worker that keeps sweeping it, and every later
// sweep is one task a worker, of all its chunks. The solution, and so the image, has the bits of
// a local Jacobi solve for any split.
TEST_F(Farm, RadiosityJacobiSweepsInPatchGroupTasksGiveTheLocalPixels) {
    // Each sweep's input and the solution through the blob store, as a large scene's are (the
    // other radiosity tests send them with the leases).
    StartServer(10, "127.0.0.1:0", {"--inline-radiosity-bytes", "0"});
    StartWorker("w1");
    StartWorker("w2");
    // The illuminance comes from the swept irradiance (and the lights' direct part each worker
    // computes again): the same bits too.
    const std::string flags = "--method radiosity --patches 300 --solver jacobi --aov illuminance";
    int chunks = 0;
    for (int sweep_tasks : {3, 5}) {
        const std::string job = Submit(scene_, "--spp 2 --seed 6 --tile 16 --sweep-tasks " +
                                                   std::to_string(sweep_tasks) + " " + flags);
        ExpectSameAsLocal(job, scene_, 2, 6, flags);
        chunks += sweep_tasks;
    }
    const std::string logs = ReadText(dir_ / "w1.log") + ReadText(dir_ / "w2.log");
    int built = 0;
    for (size_t at = 0; (at = logs.find("form factors of chunk", at)) != std::string::npos; ++at) {
        ++built;
    }
    EXPECT_EQ(built, chunks) << "a chunk's form factors were computed twice:\n" << logs;
    const std::string server_log = ReadText(dir_ / "server-1.log");
    EXPECT_NE(server_log.find("radiosity sweep 2: relative residual"), std::string::npos);
    // Sweep 2 of each job: a task a worker (two at most), one of them of several chunks (five
    // chunks over two workers).
    int sweep2 = 0;
    for (size_t at = 0;
         (at = logs.find("leased: radiosity sweep 2 patch group", at)) != std::string::npos; ++at) {
        ++sweep2;
    }
    EXPECT_GE(sweep2, 2) << logs;
    EXPECT_LE(sweep2, 4) << logs;
    EXPECT_NE(logs.find("leased: radiosity sweep 2 patch groups "), std::string::npos) << logs;
    // The scene's blob and the radiosity's: a sweep's input and the solution of each job.
    int blobs = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_ / "data" / "blobs")) {
        blobs += entry.is_regular_file();
    }
    EXPECT_GE(blobs, 1 + 2 * 2);
}

// A sphere is meshed for radiosity (PrepareSceneFor) on every worker as `lightfarm render`
// meshes it: the submission takes it, and the swept solve and the tiles give the local bits.
TEST_F(Farm, RadiosityOfASceneWithASphereGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string sphere = (dir_ / "sphere.json").string();
    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["shapes"].push_back({{"type", "sphere"},
                               {"name", "ball"},
                               {"material", "white"},
                               {"center", {0.4, 0.07, 0.13}},
                               {"radius", 0.07}});
    std::ofstream(sphere) << scene.dump();
    const std::string flags = "--method radiosity --patches 300 --solver jacobi";
    const std::string job = Submit(sphere, "--spp 2 --seed 6 --tile 16 --sweep-tasks 3 " + flags);
    ExpectSameAsLocal(job, sphere, 2, 6, flags);
}

// One command line, two ways: `lightfarm render FLAGS` and `lightfarm submit FLAGS` then
// `fetch` give the same pixels and the same header but for timings, whatever the method: path,
// radiosity with its default solver (jacobi, which the farm solves in sweeps), adaptive, whitted.
TEST_F(Farm, SameCommandLineGivesTheSameImageAndHeaderLocallyAndOnTheFarm) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    int run = 0;
    for (const std::string flags :
         {"--spp 4 --seed 2 --tile 16", "--method radiosity --patches 300 --spp 2 --tile 16",
          "--spp 4 --seed 3 --tile 16 --target-error 0.1 --max-spp 256",
          "--method whitted --spp 4 --seed 5 --tile 16"}) {
        SCOPED_TRACE(flags);
        const std::string job = Submit(scene_, flags);
        const CliRun watch = Farmctl("watch " + job);
        ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
        const std::string farm = (dir_ / (job + ".exr")).string();
        const CliRun fetch = Farmctl("fetch " + job + " -o " + farm);
        ASSERT_EQ(fetch.status, 0) << fetch.out << fetch.err;
        const std::string local = (dir_ / ("local" + std::to_string(++run) + ".exr")).string();
        const CliRun r =
            Lightfarm("render " + scene_ + " -o " + local + " " + flags + " --no-progress");
        ASSERT_EQ(r.status, 0) << r.out << r.err;
        ExpectSameImageAndHeader(farm, local);
        // A finished job shows every task done, a radiosity solve's sweeps and all.
        const TaskCounts tasks = Tasks(job);
        EXPECT_EQ(tasks.done, tasks.total);
        EXPECT_GT(tasks.total, 0);
    }
}

// fetch -o out.png writes the same preview `render -o out.png` writes from the same command
// line (exposure and tone curve included), and --png adds it beside the EXR; no temporary file
// is left behind.
TEST_F(Farm, FetchWritesThePngPreviewAsRenderDoes) {
    StartServer();
    StartWorker("w1");
    const std::string flags = "--spp 2 --seed 4 --tile 16";
    const std::string preview = " --exposure 1.5 --tonemap filmic";
    const std::string job = Submit(scene_, flags);
    ASSERT_EQ(Farmctl("watch " + job).status, 0);
    const fs::path fetched = dir_ / "fetched";
    fs::create_directories(fetched);
    const std::string png = (fetched / "farm.png").string();
    const CliRun fetch = Farmctl("fetch " + job + " -o " + png + preview);
    ASSERT_EQ(fetch.status, 0) << fetch.out << fetch.err;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(fetched)) {
        names.push_back(e.path().filename().string());
    }
    EXPECT_EQ(names, std::vector<std::string>{"farm.png"});
    const std::string exr = (dir_ / "farm.exr").string(), beside = (dir_ / "beside.png").string();
    const CliRun both = Farmctl("fetch " + job + " -o " + exr + " --png " + beside + preview);
    ASSERT_EQ(both.status, 0) << both.out << both.err;
    EXPECT_NE(both.out.find(exr + " and " + beside), std::string::npos) << both.out;
    const std::string local = (dir_ / "local.png").string();
    const CliRun r =
        Lightfarm("render " + scene_ + " -o " + local + " " + flags + preview + " --no-progress");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(ReadText(png), ReadText(local));
    EXPECT_EQ(ReadText(beside), ReadText(local));
    EXPECT_TRUE(ReadExr(exr).ok());
}

// End to end (needs the sampling pipeline of issue 13 on the wire and in the workers): --clamp,
// --aov and --filter give the same image and header on the farm as locally.
// The other Farm tests render with the default sampler (sobol) and light sampling (bvh); this
// one with the others, which `status` names.
TEST_F(Farm, ClampAovsFilterSamplerAndLightSamplingGiveTheSameImageAndHeaderLocallyAndOnTheFarm) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags =
        "--spp 4 --seed 2 --tile 16 --clamp 2 --aov all,illuminance "
        "--filter blackman-harris:2 --sampler independent --light-sampling power";
    const std::string job = Submit(scene_, flags);
    ASSERT_EQ(Farmctl("watch " + job).status, 0);
    const CliRun status = Farmctl("status " + job);
    EXPECT_NE(status.out.find("independent sampler, power light sampling"), std::string::npos)
        << status.out;
    const std::string farm = (dir_ / "farm.exr").string(), local = (dir_ / "local.exr").string();
    ASSERT_EQ(Farmctl("fetch " + job + " -o " + farm + " --false-color lux").status, 0);
    const CliRun r = Lightfarm("render " + scene_ + " -o " + local + " " + flags +
                               " --false-color lux --no-progress");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    ExpectSameImageAndHeader(farm, local);
    // The false-colour PNGs of the same lux are the same bytes.
    EXPECT_EQ(ReadText((dir_ / "farm.falsecolor.png").string()),
              ReadText((dir_ / "local.falsecolor.png").string()));
    absl::StatusOr<ExrFile> file = ReadExr(farm);
    ASSERT_TRUE(file.ok()) << file.status();
    ASSERT_TRUE(file->attributes.count("lightfarm.clamp") &&
                file->attributes.count("lightfarm.aovs"));
    EXPECT_EQ(std::get<double>(file->attributes.at("lightfarm.clamp")), 2.0);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.aovs")),
              "albedo,normal,depth,illuminance");
    EXPECT_NE(std::get<std::string>(file->attributes.at("lightfarm.units")).find("lux"),
              std::string::npos);
    EXPECT_NE(file->image.FindChannel("illuminance"), nullptr);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.filter")),
              "blackman-harris 2 px");
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.sampler")), "independent");
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.lightSampling")), "power");
    EXPECT_NE(file->image.FindChannel("depth.Z"), nullptr);
}

// A port nothing listens on now, for a server started later.
std::string ReservePort() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    socklen_t len = sizeof addr;
    const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
                    getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0;
    close(fd);
    return ok ? "127.0.0.1:" + std::to_string(ntohs(addr.sin_port)) : "";
}

// docs/farm.md: clients ride out a server restart. A submit started while the server is down
// waits for it (saying so on stderr) and gets its job; so does a watch started during an
// outage.
TEST_F(Farm, SubmitAndWatchRideOutAServerThatIsDown) {
    address_ = ReservePort();
    ASSERT_FALSE(address_.empty());
    auto wait_for_log = [&](const std::string& log, const std::string& text) {
        const auto deadline = Clock::now() + milliseconds(10000);
        while (ReadText(dir_ / log).find(text) == std::string::npos) {
            if (Clock::now() > deadline) return false;
            std::this_thread::sleep_for(milliseconds(20));
        }
        return true;
    };
    Child* submit = Spawn({std::string(LF_BIN_DIR) + "/lightfarm", "submit", scene_, "--spp", "2",
                           "--server", address_},
                          "submit.log");
    ASSERT_TRUE(wait_for_log("submit.log", "retrying")) << ReadText(dir_ / "submit.log");
    StartServer(10, address_);
    const std::string job = submit->ReadLine(milliseconds(20000));
    EXPECT_EQ(submit->Wait(milliseconds(5000)), std::optional<int>(0));
    ASSERT_EQ(job.rfind("job-", 0), 0u) << job;

    server_->Signal(SIGKILL);
    ASSERT_TRUE(server_->Wait(milliseconds(5000)));
    const auto outage_start = Clock::now();
    Child* watch = Spawn(
        {std::string(LF_BIN_DIR) + "/lightfarm", "watch", job, "--server", address_}, "watch.log");
    ASSERT_TRUE(wait_for_log("watch.log", "retrying")) << ReadText(dir_ / "watch.log");
    // An outage longer than the ten one-second retries after which `watch` used to give up.
    std::this_thread::sleep_until(outage_start + milliseconds(12000));
    ASSERT_FALSE(watch->Wait(milliseconds(0)).has_value()) << ReadText(dir_ / "watch.log");
    StartServer(10, address_);
    StartWorker("w1");
    EXPECT_EQ(watch->Wait(milliseconds(20000)), std::optional<int>(0))
        << ReadText(dir_ / "watch.log");
    EXPECT_NE(Farmctl("list").out.find(job), std::string::npos);
}

// The solve is not recorded: a server killed mid-solve starts it again, to the same bits.
TEST_F(Farm, ServerKilledMidSolveStillGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags = "--method radiosity --patches 300 --solver jacobi";
    const std::string job = Submit(scene_, "--spp 2 --seed 8 --tile 16 " + flags);
    ASSERT_TRUE(WaitForText(dir_ / "server-1.log", "radiosity sweep 3:", milliseconds(60000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 2, 8, flags);
    EXPECT_NE(ReadText(dir_ / "server-2.log").find("radiosity sweep 1:"), std::string::npos);
}

// Hierarchical radiosity solves in the same sweeps, each patch-group task linking and gathering
// its receiver clusters: a worker killed mid-sweep and a server killed mid-solve change nothing,
// so the image has the bits of `lightfarm render --radiosity hierarchical`.
TEST_F(Farm, HierarchicalSweepsSurviveAWorkerKillAndAServerRestartWithTheLocalPixels) {
    StartServer(/*lease_seconds=*/1);
    Child* doomed = StartWorker("doomed");
    StartWorker("survivor");
    const std::string flags =
        "--method radiosity --patches 1500 --radiosity hierarchical --link-error 1e-4 "
        "--aov illuminance";
    const std::string job = Submit(scene_, "--spp 2 --seed 8 --tile 16 --sweep-tasks 3 " + flags);
    ASSERT_TRUE(KillMidTask(doomed, "doomed.log"));
    ASSERT_TRUE(WaitForText(dir_ / "server-1.log", "radiosity sweep 3:", milliseconds(60000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 2, 8, flags);
    EXPECT_NE(ReadText(dir_ / "server-2.log").find("radiosity sweep 1:"), std::string::npos);
    EXPECT_NE(ReadText(dir_ / "survivor.log").find("radiosity sweep"), std::string::npos);
}

// Adaptive sampling on the farm: passes only for the tiles whose estimated error is above the
// target, each tile's passes decided by its own samples, so the same pixels as local mode.
TEST_F(Farm, TargetErrorPlansPassesOnlyWhereNeededAndGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags = "--method path --tile 16 --target-error 0.08 --max-spp 2048";
    const std::string job = Submit(scene_, "--spp 4 --seed 5 " + flags);
    ExpectSameAsLocal(job, scene_, 4, 5, flags);
    absl::StatusOr<ExrFile> exr = ReadExr((dir_ / (job + ".exr")).string());
    ASSERT_TRUE(exr.ok()) << exr.status();
    const ExrAttributes& a = exr->attributes;
    EXPECT_EQ(std::get<double>(a.at("lightfarm.targetError")), 0.08);
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.adaptive.timedOut")), "no");
    EXPECT_EQ(std::get<int>(a.at("lightfarm.adaptive.tilesAboveTarget")), 0);
    EXPECT_LE(std::get<double>(a.at("lightfarm.adaptive.worstTileError")), 0.08);
    EXPECT_GT(std::get<double>(a.at("lightfarm.estimatedError")), 0);
    // The 16 tiles did not all need the same: some stopped far below the worst one.
    const int min_spp = std::get<int>(a.at("lightfarm.adaptive.minSpp"));
    const int max_spp = std::get<int>(a.at("lightfarm.adaptive.maxSpp"));
    EXPECT_LE(4 * min_spp, max_spp) << min_spp << " to " << max_spp;
    EXPECT_GT(Tasks(job).total, 16);
}

TEST_F(Farm, ServerKilledMidAdaptiveRenderReplansTheSamePasses) {
    StartServer();
    StartWorker("w1");
    const std::string flags = "--method path --tile 16 --target-error 0.08 --max-spp 2048";
    const std::string job = Submit(scene_, "--spp 4 --seed 6 " + flags);
    ASSERT_TRUE(WaitForTasksDone(job, 20, milliseconds(30000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 4, 6, flags);
    EXPECT_NE(ReadText(dir_ / "server-2.log").find("recovered"), std::string::npos);
}

// Per-pixel adaptive sampling on the farm: passes carry the masks of the pixels not converged,
// each pixel's stop decided by its own samples, so the local pixels; after a server restart the
// recorded results replan the same masks.
TEST_F(Farm, NoiseThresholdSamplesPixelsApartAndGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags = "--method path --tile 16 --noise-threshold 0.05 --max-spp 512";
    const std::string job = Submit(scene_, "--spp 8 --seed 5 " + flags);
    ASSERT_TRUE(WaitForTasksDone(job, 24, milliseconds(30000)));
    CrashAndRestartServer();
    ExpectSameAsLocal(job, scene_, 8, 5, flags);
    absl::StatusOr<ExrFile> exr = ReadExr((dir_ / (job + ".exr")).string());
    ASSERT_TRUE(exr.ok()) << exr.status();
    const ExrAttributes& a = exr->attributes;
    EXPECT_EQ(std::get<double>(a.at("lightfarm.noiseThreshold")), 0.05);
    EXPECT_EQ(std::get<int>(a.at("lightfarm.adaptive.minSpp")), 8);
    // Pixels of one tile stopped apart: the spp channel holds more counts than tiles do passes.
    const std::vector<float>& spp = *exr->image.FindChannel("spp");
    const std::set<float> counts(spp.begin(), spp.end());
    EXPECT_GE(counts.size(), 4u);
    EXPECT_GT(Tasks(job).total, 16);
}

// The job ends because of its limit (the server says so, and so does the header), with fewer
// samples than the job asked for at most.
TEST_F(Farm, TimeLimitEndsAnAdaptiveJob) {
    StartServer();
    StartWorker("w1");
    // Without the limit this would sample up to 2^20 per pixel: hours.
    const std::string job =
        Submit(scene_, "--spp 2 --tile 32 --time-limit 2 --max-spp 1048576 --method path");
    const CliRun watch = Farmctl("watch " + job, 60);
    ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
    const std::string out = (dir_ / "timed.exr").string();
    ASSERT_EQ(Farmctl("fetch " + job + " -o " + out).status, 0);
    absl::StatusOr<ExrFile> exr = ReadExr(out);
    ASSERT_TRUE(exr.ok()) << exr.status();
    EXPECT_EQ(std::get<std::string>(exr->attributes.at("lightfarm.adaptive.timedOut")), "yes");
    EXPECT_GE(std::get<int>(exr->attributes.at("lightfarm.adaptive.minSpp")), 2);
    EXPECT_LT(std::get<int>(exr->attributes.at("lightfarm.adaptive.maxSpp")), 1048576);
    EXPECT_NE(ReadText(dir_ / "server-1.log").find("time limit of 2 s reached"), std::string::npos);
}

// A radiosity target refines the mesh, which the sweeps cannot split: every worker refines and
// solves the same system to the same bits, and the display tiles are sampled adaptively.
TEST_F(Farm, RadiosityTargetErrorRefinesOnEveryWorkerAndGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string flags =
        "--method radiosity --patches 150 --solver jacobi --tile 16 --target-error 0.2 "
        "--max-patches 600 --max-spp 64";
    const std::string job = Submit(scene_, "--spp 2 --seed 4 " + flags);
    ExpectSameAsLocal(job, scene_, 2, 4, flags);
    const std::string logs = ReadText(dir_ / "w1.log") + ReadText(dir_ / "w2.log");
    EXPECT_NE(logs.find("refinement pass 2"), std::string::npos);
    EXPECT_EQ(logs.find("form factors of chunk"), std::string::npos);
    EXPECT_EQ(ReadText(dir_ / "server-1.log").find("radiosity sweep"), std::string::npos);
}

TEST_F(Farm, RadiosityJobForAMaskedSceneIsRefusedAtSubmission) {
    StartServer();
    const std::string masked = (dir_ / "masked.json").string();
    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["materials"]["white"] = {{"type", "principled"}, {"alpha_mode", "mask"}};
    std::ofstream(masked) << scene.dump();
    const CliRun r = Farmctl("submit " + masked + " --method radiosity");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("has an alpha mask, which radiosity does not model"), std::string::npos)
        << r.err;
}

// A --sky map outside the scene's folder travels with the scene's files (by its name relative to
// that folder, which the header records) and gives the local bits.
TEST_F(Farm, SkyMapIsUploadedAndGivesTheLocalBits) {
    StartServer();
    StartWorker("w1");
    fs::create_directories(dir_ / "maps");
    std::ofstream(dir_ / "maps" / "sky.hdr", std::ios::binary)
        << lf::testing::HdrBytes(4, 2, {1, 2, 3, 4, 4, 4, 0, 1, 0, 9, 9, 9,  //
                                        0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1});
    fs::create_directories(dir_ / "scene");
    const std::string scene = (dir_ / "scene" / "cornell.json").string();
    fs::copy_file(scene_, scene);
    const std::string flags =
        "--spp 4 --seed 2 --tile 16 --sky " + (dir_ / "maps" / "sky.hdr").string();
    const std::string job = Submit(scene, flags);
    const CliRun watch = Farmctl("watch " + job);
    ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
    const std::string farm = (dir_ / "farm.exr").string(), local = (dir_ / "local.exr").string();
    ASSERT_EQ(Farmctl("fetch " + job + " -o " + farm).status, 0);
    const CliRun r = Lightfarm("render " + scene + " -o " + local + " " + flags + " --no-progress");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    ExpectSameImageAndHeader(farm, local);
    absl::StatusOr<ExrFile> file = ReadExr(farm);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.sky")), "../maps/sky.hdr");
}

// A grid medium's .vdb travels as a blob like a mesh (submit uploads what the loader reads) and
// the farm's render has the local bits; a method that does not render the medium is refused at
// submission naming both.
TEST_F(Farm, GridMediumFileIsUploadedAndGivesTheLocalBits) {
    StartServer();
    StartWorker("w1");
    fs::create_directories(dir_ / "scene" / "cache");
    std::ofstream(dir_ / "scene" / "cache" / "smoke.vdb", std::ios::binary)
        << lf::testing::VdbBytes({lf::testing::ConstantGrid("density", 0.5f, 8, 0.05)});
    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["media"] = {{"smoke",
                       {{"type", "grid"},
                        {"file", "cache/smoke.vdb"},
                        {"sigma_s", {2, 2, 2}},
                        {"transform", {{"translate", {0.1, 0.1, 0.1}}}}}}};
    scene["camera"]["medium"] = "smoke";
    const std::string smoky = (dir_ / "scene" / "smoke.json").string();
    std::ofstream(smoky) << scene.dump();
    const std::string job = Submit(smoky, "--spp 4 --seed 2 --tile 16");
    ExpectSameAsLocal(job, smoky, 4, 2);
    const CliRun ppm = Farmctl("submit " + smoky + " --method ppm --spp 4");
    EXPECT_NE(ppm.status, 0);
    EXPECT_NE(ppm.err.find("method ppm: the camera is in medium \"smoke\": not yet supported "
                           "by ppm; use --method path"),
              std::string::npos)
        << ppm.err;
}

// Files named inside files (an OBJ's MTL, the MTL's texture) are uploaded with the scene: the
// server finds them, and a worker renders the textured radiosity (which averages the texture
// per patch) with local mode's bits, which it could not without the texture.
TEST_F(Farm, FilesAnObjNamesAreUploadedWithTheScene) {
    StartServer();
    StartWorker("w1");
    fs::create_directories(dir_ / "models");
    std::ofstream(dir_ / "models" / "box.obj")
        << "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl wood\nf 1/1 2/1 3/1\n";
    std::ofstream(dir_ / "models" / "box.mtl") << "newmtl wood\nKd 0.5 0.5 0.5\nmap_Kd wood.png\n";
    std::ofstream(dir_ / "models" / "wood.png", std::ios::binary)
        << lf::testing::PngBytes(1, 1, 3, {200, 100, 50});
    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["shapes"].push_back({{"type", "mesh"}, {"file", "models/box.obj"}});
    const std::string textured = (dir_ / "textured.json").string();
    std::ofstream(textured) << scene.dump();
    const std::string flags = "--method radiosity --patches 300";
    const std::string job = Submit(textured, "--spp 2 --seed 3 --tile 16 " + flags);
    ExpectSameAsLocal(job, textured, 2, 3, flags);
}

TEST_F(Farm, JobsAboveTheLimitsAreRefusedWithTheLimitNamed) {
    StartServer(10, "127.0.0.1:0", {"--max-resolution", "32", "--max-spp", "100"});
    const CliRun big = Farmctl("submit " + scene_ + " --spp 4");
    EXPECT_NE(big.status, 0);
    EXPECT_NE(big.err.find("64x64 is above this server's limit of 32"), std::string::npos)
        << big.err;
    const std::string small = WriteScene("cornell16.json", 16);
    const CliRun many = Farmctl("submit " + small + " --spp 200");
    EXPECT_NE(many.status, 0);
    EXPECT_NE(many.err.find("--max-spp"), std::string::npos) << many.err;
    EXPECT_EQ(Farmctl("list").out.find("job-"), std::string::npos) << "nothing was queued";
    StartWorker("w1");
    EXPECT_EQ(Farmctl("watch " + Submit(small, "--spp 100")).status, 0);
}

TEST_F(Farm, ServerRefusesADataDirItCannotUse) {
    std::ofstream(dir_ / "file") << "x";
    Child* server = Spawn({std::string(LF_BIN_DIR) + "/lightfarm-server", "--listen", "127.0.0.1:0",
                           "--data-dir", (dir_ / "file" / "data").string()},
                          "server.log");
    EXPECT_EQ(server->Wait(milliseconds(5000)), std::optional<int>(1));
    EXPECT_NE(ReadText(dir_ / "server.log").find((dir_ / "file" / "data").string()),
              std::string::npos);
}

TEST_F(Farm, SecondServerOnAPortInUseRefusesToStart) {
    StartServer();
    Child* second = Spawn({std::string(LF_BIN_DIR) + "/lightfarm-server", "--listen", address_,
                           "--data-dir", (dir_ / "other-data").string()},
                          "second-server.log");
    EXPECT_EQ(second->Wait(milliseconds(10000)), std::optional<int>(1));
    const std::string log = ReadText(dir_ / "second-server.log");
    EXPECT_NE(log.find("cannot listen on " + address_), std::string::npos) << log;
    EXPECT_EQ(Farmctl("list").status, 0) << "the first server still answers";
}

TEST_F(Farm, SecondServerOnADataDirInUseRefusesToStart) {
    StartServer();
    Child* second = Spawn({std::string(LF_BIN_DIR) + "/lightfarm-server", "--listen", "127.0.0.1:0",
                           "--data-dir", (dir_ / "data").string()},
                          "second-server.log");
    EXPECT_EQ(second->Wait(milliseconds(10000)), std::optional<int>(1));
    const std::string log = ReadText(dir_ / "second-server.log");
    EXPECT_NE(log.find((dir_ / "data").string() + " is in use by another lightfarm-server (pid " +
                       std::to_string(server_->pid()) + ","),
              std::string::npos)
        << log;
}

// Issue 27: two workers on one --cache-dir evicted each other's blobs and nothing said so; the
// second now refuses to start, naming the folder and the first worker's pid.
TEST_F(Farm, SecondWorkerOnACacheDirInUseRefusesToStart) {
    StartServer();
    Child* first = StartWorker("shared");
    const fs::path lock = dir_ / "cache-shared" / "lock";
    const std::string pid = std::to_string(first->pid());
    for (int i = 0; i < 1000 && ReadText(lock) != pid + "\n"; ++i) {
        std::this_thread::sleep_for(milliseconds(10));
    }
    ASSERT_EQ(ReadText(lock), pid + "\n") << "the first worker holds the folder";
    Child* second = Spawn({std::string(LF_BIN_DIR) + "/lightfarm-worker", "--server", address_,
                           "--cache-dir", (dir_ / "cache-shared").string()},
                          "second-worker.log");
    EXPECT_EQ(second->Wait(milliseconds(10000)), std::optional<int>(1));
    const std::string log = ReadText(dir_ / "second-worker.log");
    EXPECT_NE(log.find("cache folder " + (dir_ / "cache-shared").string() +
                       " is in use by another lightfarm-worker (pid " + pid + ","),
              std::string::npos)
        << log;
    EXPECT_FALSE(first->Wait(milliseconds(0)).has_value()) << "the first worker goes on";
}

TEST_F(Farm, ListFollowsItsLimitAndDeleteRemovesOnlyEndedJobs) {
    StartServer();
    const std::string small = WriteScene("cornell16.json", 16);
    std::vector<std::string> jobs;
    for (int i = 0; i < 3; ++i) jobs.push_back(Submit(small, "--spp 4"));  // no worker: queued
    const CliRun two = Farmctl("list --limit 2");
    ASSERT_EQ(two.status, 0) << two.err;
    EXPECT_NE(two.out.find(jobs[2]), std::string::npos) << two.out;
    EXPECT_NE(two.out.find(jobs[1]), std::string::npos) << two.out;
    EXPECT_EQ(two.out.find(jobs[0]), std::string::npos) << "newest first, two only: " << two.out;

    const CliRun queued = Farmctl("delete " + jobs[0]);
    EXPECT_NE(queued.status, 0);
    EXPECT_NE(queued.err.find("cancel it"), std::string::npos) << queued.err;
    ASSERT_EQ(Farmctl("cancel " + jobs[0]).status, 0);
    const CliRun deleted = Farmctl("delete " + jobs[0]);
    EXPECT_EQ(deleted.status, 0) << deleted.err;
    EXPECT_EQ(Farmctl("list").out.find(jobs[0]), std::string::npos);
    EXPECT_NE(Farmctl("status " + jobs[0]).status, 0);
}

// What an operator trips on: a failed `list` prints no table header for a script to read;
// `logs --task` of a task the job lacks is an error; every binary answers --version alike;
// counts of one are singular.
TEST_F(Farm, OperatorMistakesGetClearAnswers) {
    const CliRun down = Lightfarm("list --server 127.0.0.1:1");
    EXPECT_NE(down.status, 0);
    EXPECT_EQ(down.out, "") << "a failed list prints nothing to stdout";
    EXPECT_NE(down.err.find("127.0.0.1:1"), std::string::npos) << down.err;

    const std::string version = Lightfarm("--version").out;
    ASSERT_FALSE(version.empty());
    for (const char* binary : {"lightfarm-server", "lightfarm-worker"}) {
        const auto [status, out] = RunBinary(std::string(binary) + " --version");
        EXPECT_EQ(status, 0) << binary;
        EXPECT_EQ(out, version) << binary;
    }

    StartServer();
    StartWorker("w1", 1);
    const std::string job = Submit(WriteScene("cornell16.json", 16), "--spp 2 --tile 8 --passes 1");
    ASSERT_EQ(Farmctl("watch " + job).status, 0);
    const CliRun missing = Farmctl("logs " + job + " --task 999");
    EXPECT_NE(missing.status, 0);
    EXPECT_EQ(missing.out, "");
    EXPECT_NE(missing.err.find("job " + job + " has no task 999: it has 4 tasks"),
              std::string::npos)
        << missing.err;
    EXPECT_EQ(Farmctl("logs " + job + " --task 3").status, 0) << "the last task is there";

    const std::string status = Farmctl("status " + job).out;
    EXPECT_NE(status.find("tile 8, 1 pass\n"), std::string::npos) << status;
    EXPECT_NE(ReadText(dir_ / "w1.log").find(" with 1 thread ("), std::string::npos);
}

// `submit` uploads every file the scene names as `render` finds it, `../` and absolute names
// included, and the farm loads them by those names from the uploads alone: the same pixels.
TEST_F(Farm, SceneWithParentAndAbsoluteMeshNamesGivesTheLocalPixels) {
    fs::create_directories(dir_ / "scenes");
    fs::create_directories(dir_ / "meshes");
    fs::create_directories(dir_ / "elsewhere");
    std::ofstream(dir_ / "meshes" / "a.obj")
        << "v 0.1 0.1 0.2\nv 0.3 0.1 0.2\nv 0.1 0.3 0.25\nf 1 2 3\n";
    std::ofstream(dir_ / "elsewhere" / "b.obj")
        << "v 0.3 0.2 0.3\nv 0.45 0.2 0.3\nv 0.3 0.4 0.35\nf 1 2 3\n";
    nlohmann::json scene = nlohmann::json::parse(ReadText(scene_));
    scene["shapes"].push_back(
        {{"type", "mesh"}, {"material", "white"}, {"file", "../meshes/a.obj"}});
    scene["shapes"].push_back(
        {{"type", "mesh"}, {"material", "red"}, {"file", (dir_ / "elsewhere" / "b.obj").string()}});
    const std::string path = (dir_ / "scenes" / "s.json").string();
    std::ofstream(path) << scene.dump(1);
    StartServer();
    StartWorker("w1");
    ExpectSameAsLocal(Submit(path, "--spp 4 --seed 3"), path, 4, 3);
}

// SIGTERM in the middle of a radiosity task (form factors of 12k patches: half a minute) stops
// the worker in the form factors, handing the task back.
TEST_F(Farm, TerminatedWorkerStopsARadiosityTask) {
    StartServer();
    Child* worker = StartWorker("w1");
    const std::string job =
        Submit(scene_, "--method radiosity --solver gauss-seidel --patches 12000");
    ASSERT_TRUE(WaitForStatus(job, "1 running", milliseconds(20000)));
    // Meshed (the radiosity log says so): the form factors have begun.
    ASSERT_TRUE(WaitForText(dir_ / "w1.log", "unknowns", milliseconds(20000)))
        << "the worker never meshed the scene";
    worker->Signal(SIGTERM);
    ASSERT_EQ(worker->Wait(kStopWithin), std::optional<int>(0));
    const std::string log = ReadText(dir_ / "w1.log");
    EXPECT_NE(log.find("handed back"), std::string::npos);
    // PrepareRadiosity logs "form factors in N s" once they are done: they never were.
    EXPECT_EQ(log.find("form factors in"), std::string::npos) << log;
}

// The textured glTF of the import tests, its quad glowing so the image is not black: a .gltf
// with its .bin and image in a folder of their own, and a .glb with the image beside it.
struct GltfFiles {
    std::string gltf, glb;
    std::vector<std::string> hashes;  // of every file the .gltf scene reads, itself included
};

GltfFiles WriteGltfScene(const fs::path& dir) {
    fs::create_directories(dir);
    testing::GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["emissiveFactor"] = {1, 0.5, 0.25};
    b.json()["materials"][0]["emissiveTexture"] = {{"index", 0}};
    const std::string gltf = b.Gltf("scene.bin"), glb = b.Glb();
    const std::string png = testing::PngBytes(2, 2, 4, testing::TestTexels());
    std::ofstream(dir / "scene.gltf", std::ios::binary) << gltf;
    std::ofstream(dir / "scene.bin", std::ios::binary) << b.bin();
    std::ofstream(dir / "scene.glb", std::ios::binary) << glb;
    std::ofstream(dir / "tex.png", std::ios::binary) << png;
    std::ofstream(dir / "unrelated.png", std::ios::binary) << png + "x";
    return {(dir / "scene.gltf").string(),
            (dir / "scene.glb").string(),
            {Sha256Hex(gltf), Sha256Hex(b.bin()), Sha256Hex(png)}};
}

TEST_F(Farm, TexturedGltfSceneGivesTheLocalPixels) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const GltfFiles files = WriteGltfScene(dir_ / "gltf");
    const std::string flags = "--method path --resolution 48x32 --camera Front";
    const std::string job = Submit(files.gltf, "--spp 8 --seed 5 --tile 16 " + flags);
    ExpectSameAsLocal(job, files.gltf, 8, 5, flags);
    // Another seed: ExpectSameAsLocal keeps local renders by spp, seed and flags.
    const std::string glb_job = Submit(files.glb, "--spp 8 --seed 6 --tile 16 " + flags);
    ExpectSameAsLocal(glb_job, files.glb, 8, 6, flags);
    // A JSON scene in another folder including the glTF by a relative name: its buffer and
    // image are uploaded by the names the loader asked for ("../gltf/scene.bin").
    fs::create_directories(dir_ / "json");
    std::ofstream(dir_ / "json" / "lit.json")
        << R"({"materials": {}, "shapes": [{"type": "gltf", "file": "../gltf/scene.gltf",)"
           R"( "transform": {"translate": [0, 0.5, 0]}}], "lights": [{"type": "point",)"
           R"( "position": [2, 3, 3], "intensity": [5, 5, 5]}]})";
    const std::string json = (dir_ / "json" / "lit.json").string();
    const std::string json_job = Submit(json, "--spp 8 --seed 7 --tile 16 " + flags);
    ExpectSameAsLocal(json_job, json, 8, 7, flags);
    // Uploaded: the files the loader read (the glTF, its buffer, its image), not what else
    // lies in the folder.
    std::set<std::string> blobs;
    for (const auto& e : fs::directory_iterator(dir_ / "data" / "blobs")) {
        blobs.insert(e.path().filename().string());
    }
    for (const std::string& hash : files.hashes) EXPECT_TRUE(blobs.count(hash)) << hash;
    const std::string unrelated = Sha256Hex(ReadText(dir_ / "gltf" / "unrelated.png"));
    EXPECT_FALSE(blobs.count(unrelated));
}

TEST_F(Farm, BrokenUploadResumesWhereTheServersBytesEndAndTheJobRenders) {
    StartServer();
    StartWorker("w1");
    // A texture of 24 MB that costs nothing to decode: a 2x2 PNG, then bytes a PNG reader
    // never reads (past IEND). The test is about the upload, not the image.
    fs::create_directories(dir_ / "big");
    std::string png = testing::PngBytes(2, 2, 4, testing::TestTexels());
    std::mt19937 random(16);
    std::string junk(24 << 20, '\0');
    for (char& c : junk) c = char(random());
    png += junk;
    std::ofstream(dir_ / "big" / "tex.png", std::ios::binary) << png;
    std::ofstream(dir_ / "big" / "quad.obj") << testing::TexturedTestQuadObj();
    std::ofstream(dir_ / "big" / "scene.json") << testing::TexturedTestSceneJson();
    const std::string scene = (dir_ / "big" / "scene.json").string();
    const fs::path partial =
        dir_ / "data" / "blobs" / "partial" / (Sha256Hex(png) + "-" + std::to_string(png.size()));
    const fs::path server_log = dir_ / "server-1.log";

    testing::CuttingProxy proxy(std::stoi(address_.substr(address_.rfind(':') + 1)));
    const std::string via = " --server 127.0.0.1:" + std::to_string(proxy.port());
    const std::string settings = " --spp 4 --tile 16 --resolution 48x32";

    // The connection drops 8 MB into the upload, and this submit does not retry: it fails, and
    // the server keeps the bytes that arrived.
    proxy.CutNextAfter(8 << 20);
    const CliRun first = Lightfarm("submit " + scene + settings + via + " --retry-seconds 0");
    EXPECT_NE(first.status, 0);
    EXPECT_NE(first.err.find("tex.png: upload"), std::string::npos) << first.err;
    ASSERT_EQ(proxy.connections_cut(), 1);
    ASSERT_TRUE(WaitForText(server_log, "upload from", milliseconds(10000)));
    ASSERT_TRUE(WaitForText(server_log, "ended after", milliseconds(10000)));
    const uint64_t held = fs::file_size(partial);
    EXPECT_GT(held, uint64_t(1) << 20);
    EXPECT_LT(held, png.size());

    // A second submit: its first connection drops 8 MB later too, and it retries by itself.
    // Each attempt asks the server where its bytes end and sends only the rest.
    proxy.CutNextAfter(8 << 20);
    const CliRun second = Lightfarm("submit " + scene + settings + via);
    ASSERT_EQ(second.status, 0) << second.err;
    EXPECT_EQ(proxy.connections_cut(), 2);
    EXPECT_NE(second.err.find("tex.png: the server holds"), std::string::npos) << second.err;
    // Both attempts resumed: at the bytes the first submit left, then at those the cut attempt
    // added. What a cut connection had sent but the server had not read yet (socket buffers,
    // HTTP/2 windows) is sent again, as no client can know of it.
    const std::string log = ReadText(server_log);
    std::vector<uint64_t> resumed_at;
    const std::string resumes = "resumes at byte ";
    for (size_t at = log.find(resumes); at != std::string::npos; at = log.find(resumes, at + 1)) {
        resumed_at.push_back(std::stoull(log.substr(at + resumes.size())));
    }
    ASSERT_EQ(resumed_at.size(), 2u) << log;
    EXPECT_EQ(resumed_at[0], held);
    EXPECT_GT(resumed_at[1], held);
    // The last attempt sent the rest and no more, but for the scene's small files, the calls
    // and their framing (a restart would send all 24 MB).
    const uint64_t rest = png.size() - resumed_at[1];
    EXPECT_GE(proxy.bytes_of_last_connection(), rest);
    EXPECT_LT(proxy.bytes_of_last_connection(), rest + (256 << 10)) << "rest " << rest;
    EXPECT_NE(log.find("stored, " + std::to_string(png.size()) + " bytes"), std::string::npos)
        << log;
    EXPECT_FALSE(fs::exists(partial));

    const CliRun watch = Farmctl("watch " + second.LastLine());
    EXPECT_EQ(watch.status, 0) << watch.out << watch.err;
}

TEST_F(Farm, BadGltfIsRefusedAtSubmissionWithTheLoadersMessage) {
    StartServer();
    const GltfFiles files = WriteGltfScene(dir_ / "gltf");
    nlohmann::json gltf = nlohmann::json::parse(ReadText(files.gltf));
    gltf["meshes"][1]["primitives"][0]["mode"] = 1;
    std::ofstream(files.gltf) << gltf.dump();
    const CliRun local = Lightfarm("render " + files.gltf + " -o " + (dir_ / "x.exr").string());
    const CliRun farm = Farmctl("submit " + files.gltf);
    EXPECT_NE(farm.status, 0);
    const std::string message = "meshes[1] \"tri\".primitives[0]: mode 1 (LINES) is not supported";
    EXPECT_NE(local.err.find(message), std::string::npos) << local.err;
    EXPECT_NE(farm.err.find(message), std::string::npos) << farm.err;
    // A texture missing on submission: refused before anything is uploaded.
    fs::remove(dir_ / "gltf" / "tex.png");
    const CliRun missing = Farmctl("submit " + files.glb);
    EXPECT_NE(missing.status, 0);
    EXPECT_NE(missing.err.find("images[0] \"checker\": uri \"tex.png\""), std::string::npos)
        << missing.err;
}

// The splatting methods (light paths or photon passes over the whole frame, splats merged exactly):
// on the farm, the bits and header of `lightfarm render` with the same flags, whichever worker
// renders which task, a worker killed mid-task, or the coordinator killed mid-job. bdpt and ppm
// join the list below when their kernels land (a one-line change).
TEST_F(Farm, AShotInChunksSurvivesAKilledWorkerAndARestartAndGivesRendersBits) {
    StartServer(/*lease_seconds=*/1);
    Child* doomed = StartWorker("doomed");
    StartWorker("survivor");
    // 8 frames, two a task: 4 tasks of over a second each on one thread.
    const std::string flags = std::string(kShotFlags) + " --spp 512 --tile 32";
    const std::string job = Submit(ShotScene(), "--frames 1-8 --chunk 2 " + flags);
    ASSERT_TRUE(KillMidTask(doomed, "doomed.log"));
    ASSERT_TRUE(WaitForTasksDone(job, 1, milliseconds(60000)));
    CrashAndRestartServer();
    const CliRun watch = Farmctl("watch " + job, 120);
    ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
    EXPECT_NE(watch.out.find("8/8 frames"), std::string::npos) << watch.out;
    const CliRun tasks = Farmctl("tasks " + job);
    for (const char* chunk : {" 1-2 ", " 3-4 ", " 5-6 ", " 7-8 "}) {
        EXPECT_NE(tasks.out.find(chunk), std::string::npos) << chunk << " in\n" << tasks.out;
    }
    EXPECT_GT(Tasks(job).leased, Tasks(job).total) << "the killed worker's chunk ran once";
    ExpectFramesAsRendered(job, {1, 2, 3, 4, 5, 6, 7, 8}, "1-8", flags);
}

// `lightfarm requeue --frames`: a succeeded shot's frame is rendered again from scratch, the
// requeue surviving a coordinator restart before any worker takes it, to the bits of a local
// render; frames outside the shot are refused, naming them.
TEST_F(Farm, RequeuedFrameOfASucceededShotRendersAgainAfterARestartToRendersBits) {
    StartServer();
    Child* first = StartWorker("first");
    const std::string flags = std::string(kShotFlags) + " --spp 4 --tile 32";
    const std::string job = Submit(ShotScene(), "--frames 1-3 " + flags);
    const CliRun watch = Farmctl("watch " + job, 120);
    ASSERT_EQ(watch.status, 0) << watch.out << watch.err;
    first->Signal(SIGTERM);
    ASSERT_TRUE(first->Wait(milliseconds(10000)));
    const CliRun outside = Farmctl("requeue " + job + " --frames 3-5");
    EXPECT_NE(outside.status, 0);
    EXPECT_NE(outside.err.find("frames 4, 5 not in job"), std::string::npos) << outside.err;
    const CliRun requeued = Farmctl("requeue " + job + " --failed --frames 2");
    ASSERT_EQ(requeued.status, 0) << requeued.err;
    EXPECT_EQ(requeued.out.rfind("job " + job + " queued (", 0), 0u) << requeued.out;
    CrashAndRestartServer();
    EXPECT_NE(Farmctl("status " + job).out.find(": queued"), std::string::npos);
    StartWorker("second");
    const CliRun again = Farmctl("watch " + job, 120);
    ASSERT_EQ(again.status, 0) << again.out << again.err;
    EXPECT_NE(again.out.find("3/3 frames"), std::string::npos) << again.out;
    ExpectFramesAsRendered(job, {1, 2, 3}, "1-3", flags);
}

TEST_F(Farm, ACancelledShotKeepsItsFinishedFramesFetchable) {
    StartServer();
    StartWorker("w1");
    // Frame 1 is quick, frame 2 would take minutes: the cancel lands in frame 2.
    const std::string flags = std::string(kShotFlags) + " --spp 4096 --tile 96";
    const std::string job = Submit(ShotScene(), "--frames 1-3 " + flags);
    ASSERT_TRUE(WaitForStatus(job, "1 done", milliseconds(60000)));
    ASSERT_EQ(Farmctl("cancel " + job).status, 0);
    const CliRun status = Farmctl("status " + job);
    EXPECT_NE(status.out.find("cancelled"), std::string::npos) << status.out;
    // Without --frames, fetch writes every finished frame: frame 1 alone.
    const CliRun all = Farmctl("fetch " + job + " -o " + (dir_ / "all_####.exr").string());
    ASSERT_EQ(all.status, 0) << all.out << all.err;
    EXPECT_TRUE(fs::exists(dir_ / "all_0001.exr"));
    EXPECT_FALSE(fs::exists(dir_ / "all_0002.exr"));
    // An unfinished frame asked by name is a clear error naming it.
    const CliRun unfinished =
        Farmctl("fetch " + job + " --frames 3 -o " + (dir_ / "u_####.exr").string());
    EXPECT_NE(unfinished.status, 0);
    EXPECT_NE(unfinished.err.find("frame 3"), std::string::npos) << unfinished.err;
    ExpectFramesAsRendered(job, {1}, "1", flags);
}

// The client checks a shot's flags with the code `render` uses: the same words either way.
TEST_F(Farm, AShotsBadFlagsAreRefusedAtSubmissionWithRendersMessage) {
    StartServer();
    for (const std::string bad : {"--frames 5-1", "--frames 1-0:0", "--frame 1-3", "--shutter 0.5",
                                  "--frames 1-2 --shutter 11"}) {
        SCOPED_TRACE(bad);
        const CliRun submit = Farmctl("submit " + ShotScene() + " " + bad);
        const CliRun render = Lightfarm("render " + ShotScene() + " " + bad + " -o " +
                                        (dir_ / "x_####.exr").string());
        EXPECT_NE(submit.status, 0);
        EXPECT_NE(render.status, 0);
        EXPECT_FALSE(submit.err.empty());
        EXPECT_EQ(submit.err, render.err);
    }
    const CliRun chunk = Farmctl("submit " + ShotScene() + " --chunk 2");
    EXPECT_NE(chunk.status, 0);
    EXPECT_NE(chunk.err.find("--chunk 2: whole frames a task needs a shot"), std::string::npos)
        << chunk.err;
    EXPECT_EQ(Farmctl("list").out.find("moving_ball"), std::string::npos) << "a job was made";
}

class FarmSplat : public Farm, public ::testing::WithParamInterface<std::string> {
  protected:
    std::string Flags(uint64_t spp, uint64_t seed, const std::string& more = "") const {
        return "--method " + GetParam() + " --spp " + std::to_string(spp) + " --seed " +
               std::to_string(seed) + " " + more;
    }
    // The flags local mode takes besides --spp and --seed (ExpectSameAsLocal adds those).
    std::string LocalFlags(const std::string& more = "") const {
        return "--method " + GetParam() + " " + more;
    }
    // 16 tasks of the method on the 64x64 scene: light paths in 16 ranges (splats grouped by
    // tiles of 16, unlike local mode's default); bdpt's whole frame in 16 sample passes, each
    // task's splats landing anywhere; ppm's 16 ranges of passes, with few photons a pass so
    // that hundreds of passes stay quick.
    std::string Split(uint64_t photons = 4096) const {
        if (GetParam() == "light") return "--passes 16 --tile 16";
        if (GetParam() == "bdpt") return "--passes 16 --tile 64";
        return "--passes 16 --photons " + std::to_string(photons);
    }
    // Whether the worker's log names a task of the job.
    bool WorkerTookPart(const std::string& worker, const std::string& job) {
        return ReadText(dir_ / (worker + ".log")).find("job=" + job + " task=") !=
               std::string::npos;
    }
};

INSTANTIATE_TEST_SUITE_P(Methods, FarmSplat, ::testing::Values("light", "bdpt", "ppm"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             return info.param;
                         });

// Split(): 16 tasks, whose splats land all over the frame, from both workers.
TEST_P(FarmSplat, TwoWorkersGiveTheLocalBitsAndHeader) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string job = Submit(scene_, Flags(16, 5, Split()));
    ExpectSameAsLocal(job, scene_, 16, 5, LocalFlags(Split()));
    EXPECT_EQ(Tasks(job).done, 16);
    EXPECT_TRUE(WorkerTookPart("w1", job));
    EXPECT_TRUE(WorkerTookPart("w2", job));
    const CliRun status = Farmctl("status " + job);
    EXPECT_NE(status.out.find("method    " + GetParam()), std::string::npos) << status.out;
    const CliRun list = Farmctl("list");
    EXPECT_NE(list.out.find(GetParam()), std::string::npos) << list.out;
}

TEST_P(FarmSplat, KilledWorkerDoesNotChangeTheImage) {
    StartServer(/*lease_seconds=*/1);
    Child* doomed = StartWorker("doomed");
    StartWorker("survivor");
    const std::string job = Submit(scene_, Flags(256, 9, Split()));
    ASSERT_TRUE(KillMidTask(doomed, "doomed.log"));
    ExpectSameAsLocal(job, scene_, 256, 9, LocalFlags(Split()));
    const TaskCounts c = Tasks(job);
    EXPECT_EQ(c.done, 16);
    EXPECT_GT(c.leased, c.total) << "no task was leased again";
}

// Results merged before the kill are recorded with their splats and merged once on restart; a
// result merged twice, or lost, would change the bits.
TEST_P(FarmSplat, CoordinatorKilledMidJobCompletesWithTheLocalBits) {
    StartServer();
    StartWorker("w1");
    StartWorker("w2");
    const std::string job = Submit(scene_, Flags(256, 7, Split()));
    ASSERT_TRUE(WaitForTasksDone(job, 4, milliseconds(30000)));
    CrashAndRestartServer();
    EXPECT_GE(Tasks(job).done, 2) << "acknowledged results were lost";
    ExpectSameAsLocal(job, scene_, 256, 7, LocalFlags(Split()));
    const TaskCounts c = Tasks(job);
    EXPECT_EQ(c.done, 16);
    EXPECT_LE(c.leased, 16 + 2 * 2) << "done tasks were rendered again";
}

// A running frame job's preview is the image of the light paths merged so far (normalised by
// them, so not darker than the final image would be); a cancel stops the kernel mid-task.
TEST_P(FarmSplat, PreviewShowsTheMergedPathsAndCancelStopsTheTask) {
    StartServer();
    StartWorker("w1");
    // Tasks of a second or more, so that the cancel lands mid-task: ppm's passes of 65536
    // photons, light's 1024 paths a pixel a task (with 4096 photons, or 64 light paths a pixel,
    // an idle machine often finished the task before its next heartbeat).
    const uint64_t spp = GetParam() == "light" ? 16384 : 1024;
    const std::string job = Submit(scene_, Flags(spp, 3, Split(/*photons=*/65536)));
    ASSERT_TRUE(WaitForTasksDone(job, 2, milliseconds(60000)));
    const std::string preview = (dir_ / "preview.exr").string();
    const CliRun fetch = Farmctl("fetch --preview " + job + " -o " + preview);
    ASSERT_EQ(fetch.status, 0) << fetch.err;
    absl::StatusOr<ExrFile> partial = ReadExr(preview);
    ASSERT_TRUE(partial.ok()) << partial.status();
    const std::vector<float>& r = *partial->image.FindChannel("R");
    double sum = 0;
    for (float v : r) sum += v;
    // This Cornell box's mean R is about 0.2; a preview divided by all the job's paths instead
    // of those merged (2 or 3 of 16 tasks by now) would be 5 to 8 times darker.
    EXPECT_GT(sum / double(r.size()), 0.1) << "the preview is not normalised by merged paths";
    ASSERT_TRUE(WaitForStatus(job, "1 running", milliseconds(20000)));
    // The cancel goes right after the worker leases a fresh task: light's tasks are capped at
    // 2^18 paths, about 0.6 s or two heartbeats on an idle machine, so a cancel sent at a random
    // moment often landed after the task's last heartbeat and found nothing to stop.
    const auto leases = [&] {
        const std::string text = ReadText(dir_ / "w1.log");
        size_t n = 0;
        for (size_t at = text.find(" leased: "); at != std::string::npos;
             at = text.find(" leased: ", at + 1)) {
            ++n;
        }
        return n;
    };
    const size_t leased = leases();
    const auto deadline = Clock::now() + milliseconds(20000);
    while (leases() == leased && Clock::now() < deadline)
        std::this_thread::sleep_for(milliseconds(1));
    ASSERT_GT(leases(), leased) << "the worker leased no further task";
    ASSERT_EQ(Farmctl("cancel " + job).status, 0);
    EXPECT_TRUE(WaitForText(dir_ / "w1.log", "dropped", kStopWithin))
        << "the worker still renders after the cancel";
}

// The kernels splat with the box filter only: another filter is refused at submission, naming
// the method and the filter, rather than failing on every worker.
// Light tracing and bdpt splat with the box filter only and are refused other filters at
// submission; ppm gathers at filter-sampled camera samples and renders them as locally.
TEST_P(FarmSplat, NonBoxFilterIsRefusedAtSubmissionWhereTheKernelSplats) {
    StartServer();
    const std::string filter = "--filter gaussian:2 " + Split();
    if (GetParam() == "ppm") {
        StartWorker("w1");
        const std::string job = Submit(scene_, Flags(4, 1, filter));
        ExpectSameAsLocal(job, scene_, 4, 1, LocalFlags(filter));
        return;
    }
    const CliRun r = Farmctl("submit " + scene_ + " " + Flags(4, 1, filter));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("method " + GetParam()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("gaussian"), std::string::npos) << r.err;
}

TEST(FarmSplatFlags, PhotonFlagsAreRefusedForOtherMethodsOnSubmit) {
    const std::string cmd = std::string(LF_BIN_DIR) + "/lightfarm submit " + LF_TEST_SCENES +
                            "/cornell_box.json --method light --photons 1000 "
                            "--server 127.0.0.1:1 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    EXPECT_NE(WEXITSTATUS(pclose(pipe)), 0);
    EXPECT_NE(out.find("--photons"), std::string::npos) << out;
}

// Job management (issue 30): a worker that fails every task is blocklisted from the job after
// --blocklist-after of its failures (it cannot fail any one task 3 times: a task it failed waits
// for the good worker), and the job succeeds on the good worker with the bits of a local render.
// The blocklist is in the job's record, so it outlives a restart.
TEST_F(Farm, BrokenWorkerIsBlocklistedAndTheJobSucceedsOnTheGoodOne) {
    StartServer();
    StartWorker("good");
    StartWorker("bad", 1, {"--fail-tasks-for-test"});
    ASSERT_TRUE(WaitForWorkers(2));
    const std::string job = Submit(scene_, "--spp 64 --tile 16 --seed 5 --blocklist-after 3");
    ExpectSameAsLocal(job, scene_, 64, 5);
    const std::string blocklisted =
        "(3 failures, last: failing every task (--fail-tasks-for-test) (worker ";
    const CliRun status = Farmctl("status " + job);
    EXPECT_NE(status.out.find("  blocklisted: "), std::string::npos) << status.out;
    EXPECT_NE(status.out.find(blocklisted), std::string::npos) << status.out;
    EXPECT_NE(status.out.find("attempts  3 a task; blocklist after 3 failures"), std::string::npos)
        << status.out;
    EXPECT_EQ(ReadText(dir_ / "good.log").find("failing every task"), std::string::npos);
    CrashAndRestartServer();
    EXPECT_NE(Farmctl("status " + job).out.find(blocklisted), std::string::npos);
}

// With only a broken worker, the job does not wait for ever: once the worker is blocklisted,
// no live worker may take its tasks and it fails naming the worker.
TEST_F(Farm, JobFailsWhenItsOnlyWorkerIsBlocklisted) {
    StartServer();
    StartWorker("bad", 1, {"--fail-tasks-for-test"});
    ASSERT_TRUE(WaitForWorkers(1));
    const std::string job =
        Submit(scene_, "--spp 1 --tile 16 --max-attempts 10 --blocklist-after 2");
    EXPECT_NE(Farmctl("watch " + job).status, 0);
    const CliRun status = Farmctl("status " + job);
    EXPECT_NE(status.out.find("error     every live worker is blocklisted from the job: "),
              std::string::npos)
        << status.out;
    EXPECT_NE(status.out.find(" (2 failures, last: failing every task"), std::string::npos)
        << status.out;
}

// Job management (issue 30): a job failed by its max attempts (a broken worker beside a good
// one; --max-attempts 1) keeps the results of the tasks done, across a coordinator restart:
// `requeue` queues it again with those tasks done, and it renders the rest on the good worker to
// the bits of a local render.
TEST_F(Farm, RequeuedFailedJobRendersOnAfterARestartToTheBitsOfALocalRender) {
    StartServer();
    StartWorker("good");
    Child* bad = StartWorker("bad", 1, {"--fail-tasks-for-test"});
    ASSERT_TRUE(WaitForWorkers(2));
    const std::string job = Submit(scene_, "--spp 16 --tile 16 --seed 7 --max-attempts 1");
    EXPECT_NE(Farmctl("watch " + job).status, 0);
    bad->Signal(SIGKILL);
    ASSERT_TRUE(bad->Wait(milliseconds(5000)));
    const CliRun failed = Farmctl("status " + job);
    EXPECT_NE(failed.out.find("error     task "), std::string::npos) << failed.out;
    EXPECT_NE(failed.out.find("failed 1 time; last: failing every task"), std::string::npos)
        << failed.out;
    const TaskCounts before = Tasks(job);
    CrashAndRestartServer();
    EXPECT_NE(Farmctl("status " + job).out.find(": failed"), std::string::npos);
    const CliRun requeued = Farmctl("requeue " + job);
    ASSERT_EQ(requeued.status, 0) << requeued.err;
    EXPECT_EQ(requeued.out,
              "job " + job + " queued (" + std::to_string(before.done) + "/16 tasks done)\n");
    ExpectSameAsLocal(job, scene_, 16, 7);
    const CliRun status = Farmctl("status " + job);
    EXPECT_EQ(status.out.find("error "), std::string::npos) << status.out;
    // A succeeded job has nothing to requeue.
    const CliRun again = Farmctl("requeue " + job);
    EXPECT_NE(again.status, 0);
    EXPECT_NE(again.err.find("only a failed or cancelled job is queued again"), std::string::npos)
        << again.err;
}

// Job management (issue 30): a paused job leases nothing, and stays paused across a restart;
// resumed, it renders to the bits of a local render. A worker is listed once its first lease
// request was answered under the scheduler's lock, so "nothing leased" is checked after one.
TEST_F(Farm, PausedJobStaysPausedAcrossARestartAndRendersOnceResumed) {
    StartServer();
    const std::string job = Submit(scene_, "--spp 4 --tile 32 --seed 9");
    const CliRun paused = Farmctl("pause " + job);
    ASSERT_EQ(paused.status, 0) << paused.err;
    EXPECT_EQ(paused.out, "job " + job + " paused\n");
    StartWorker("w1");
    ASSERT_TRUE(WaitForWorkers(1));
    EXPECT_EQ(Tasks(job).leased, 0);
    EXPECT_NE(Farmctl("status " + job).out.find("job " + job + ": paused"), std::string::npos);
    CrashAndRestartServer();
    ASSERT_TRUE(WaitForWorkers(1));
    EXPECT_EQ(Tasks(job).leased, 0);
    EXPECT_NE(Farmctl("list").out.find("paused"), std::string::npos);
    const CliRun resumed = Farmctl("resume " + job);
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    EXPECT_EQ(resumed.out, "job " + job + " resumed\n");
    ExpectSameAsLocal(job, scene_, 4, 9);
    EXPECT_NE(Farmctl("pause " + job).status, 0);  // it has ended
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// Dependencies (issue 30): `submit --after` and `depend` on the command line. The dependent
// waits, status and list say so, a cycle and an unknown id are refused with their names, and
// the chain renders in order once a worker comes (a waiting job leases nothing).
TEST_F(Farm, DependentWaitsForItsDependencyAndTheCliSaysWhy) {
    StartServer();
    const std::string a = Submit(scene_, "--spp 4 --tile 32 --seed 9");
    const std::string b = Submit(scene_, "--spp 4 --tile 32 --seed 9 --after " + a + "," + a);
    const CliRun unknown = Farmctl("submit " + scene_ + " --after job-nonesuch");
    EXPECT_NE(unknown.status, 0);
    EXPECT_NE(unknown.err.find("job-nonesuch"), std::string::npos) << unknown.err;
    const CliRun cycle = Farmctl("depend " + a + " --after " + b);
    EXPECT_NE(cycle.status, 0);
    EXPECT_NE(cycle.err.find("cycle: " + a + " -> " + b + " -> " + a), std::string::npos)
        << cycle.err;
    const std::string status = Farmctl("status " + b).out;
    EXPECT_NE(status.find("  after     " + a + "\n"), std::string::npos) << status;
    EXPECT_NE(status.find("  waiting   waiting for " + a + " (queued)\n"), std::string::npos)
        << status;
    const std::string list = Farmctl("list").out;
    EXPECT_NE(list.find("waiting"), std::string::npos) << list;
    const std::string c = Submit(scene_, "--spp 4 --tile 32 --seed 9");
    const CliRun depend = Farmctl("depend " + c + " --after " + b);
    ASSERT_EQ(depend.status, 0) << depend.err;
    EXPECT_EQ(depend.out, "job " + c + " runs after " + b + "; waiting for " + b + " (queued)\n");
    StartWorker("w1");
    ASSERT_TRUE(WaitForStatus(c, ": succeeded", milliseconds(60000)));
    // `status --json`: each ended before the next one's first lease.
    const auto times = [&](const std::string& job) {
        const nlohmann::json j = nlohmann::json::parse(Farmctl("status --json " + job).out);
        return std::pair{std::stoll(j.at("started_unix_ms").get<std::string>()),
                         std::stoll(j.at("finished_unix_ms").get<std::string>())};
    };
    const auto [a_started, a_finished] = times(a);
    const auto [b_started, b_finished] = times(b);
    const auto [c_started, c_finished] = times(c);
    EXPECT_LE(a_finished, b_started);
    EXPECT_LE(b_finished, c_started);
}

}  // namespace
}  // namespace lf
