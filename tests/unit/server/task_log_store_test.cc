// The task log store: lines kept in order per job, bounded per task with a counted "dropped"
// line, sanitised as wire input, paged by seq, kept across a reopen, deleted with their job; and
// ended jobs' task lists.
#include "lf/server/task_log_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class TaskLogStoreTest : public ::testing::Test {
  protected:
    void SetUp() override { dir_ = lf::testing::FreshTestDir("lf_task_logs"); }
    void TearDown() override { fs::remove_all(dir_); }

    std::unique_ptr<TaskLogStore> Open(TaskLogLimits limits = {}) {
        absl::StatusOr<std::unique_ptr<TaskLogStore>> store =
            TaskLogStore::Open((dir_ / "logs.db").string(), limits);
        EXPECT_TRUE(store.ok()) << store.status();
        return store.ok() ? std::move(*store) : nullptr;
    }

    static std::vector<TaskLogLine> Lines(const std::string& prefix, int n,
                                          const std::string& level = "info") {
        std::vector<TaskLogLine> lines(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) {
            lines[size_t(i)].time = absl::FromUnixMillis(1'700'000'000'000 + i);
            lines[size_t(i)].level = level;
            lines[size_t(i)].text = absl::StrCat(prefix, " ", i);
        }
        return lines;
    }

    static std::vector<std::string> Texts(const TaskLogPage& page) {
        std::vector<std::string> texts;
        for (const TaskLogLine& line : page.lines) texts.push_back(line.text);
        return texts;
    }

    fs::path dir_;
};

TEST_F(TaskLogStoreTest, LinesComeBackInOrderWithTheirTaskAttemptAndWorker) {
    auto store = Open();
    ASSERT_TRUE(store->Append("job-a", 3, 1, "w1", Lines("t3", 2)).ok());
    ASSERT_TRUE(store->Append("job-a", 5, 2, "w2", Lines("t5", 1, "error")).ok());
    ASSERT_TRUE(store->Append("job-b", 0, 1, "w1", Lines("other", 1)).ok());
    ASSERT_TRUE(store->Append("job-a", 3, 1, "w1", Lines("t3 more", 1)).ok());
    absl::StatusOr<TaskLogPage> page = store->Read("job-a", std::nullopt, 0, 100);
    ASSERT_TRUE(page.ok()) << page.status();
    EXPECT_EQ(Texts(*page), (std::vector<std::string>{"t3 0", "t3 1", "t5 0", "t3 more 0"}));
    const TaskLogLine& t5 = page->lines[2];
    EXPECT_EQ(t5.task, 5);
    EXPECT_EQ(t5.attempt, 2);
    EXPECT_EQ(t5.worker, "w2");
    EXPECT_EQ(t5.level, "error");
    EXPECT_EQ(t5.time, absl::FromUnixMillis(1'700'000'000'000));
    for (size_t i = 1; i < page->lines.size(); ++i) {
        EXPECT_GT(page->lines[i].seq, page->lines[i - 1].seq);
    }
    EXPECT_EQ(page->next_seq, page->lines.back().seq);

    absl::StatusOr<TaskLogPage> task3 = store->Read("job-a", 3, 0, 100);
    ASSERT_TRUE(task3.ok());
    EXPECT_EQ(Texts(*task3), (std::vector<std::string>{"t3 0", "t3 1", "t3 more 0"}));
    EXPECT_EQ((*store->LineCounts("job-a")), (std::map<int, int>{{3, 3}, {5, 1}}));
}

TEST_F(TaskLogStoreTest, PagesFollowAfterSeqWithoutGapsOrRepeats) {
    auto store = Open();
    ASSERT_TRUE(store->Append("job", 0, 1, "w", Lines("a", 5)).ok());
    absl::StatusOr<TaskLogPage> first = store->Read("job", std::nullopt, 0, 3);
    ASSERT_TRUE(first.ok());
    EXPECT_EQ(Texts(*first), (std::vector<std::string>{"a 0", "a 1", "a 2"}));
    ASSERT_TRUE(store->Append("job", 1, 1, "w", Lines("b", 1)).ok());
    absl::StatusOr<TaskLogPage> second = store->Read("job", std::nullopt, first->next_seq, 3);
    ASSERT_TRUE(second.ok());
    EXPECT_EQ(Texts(*second), (std::vector<std::string>{"a 3", "a 4", "b 0"}));
    absl::StatusOr<TaskLogPage> none = store->Read("job", std::nullopt, second->next_seq, 3);
    ASSERT_TRUE(none.ok());
    EXPECT_TRUE(none->lines.empty());
    EXPECT_EQ(none->next_seq, second->next_seq);  // the caller polls from the same place
}

TEST_F(TaskLogStoreTest, ATaskKeepsItsNewestLinesAndCountsTheDroppedOnesInOneLine) {
    auto store = Open({.max_lines_per_task = 4, .max_bytes_per_task = 1 << 20});
    ASSERT_TRUE(store->Append("job", 0, 1, "w", Lines("x", 3)).ok());
    ASSERT_TRUE(store->Append("job", 1, 1, "w", Lines("other", 2)).ok());
    ASSERT_TRUE(store->Append("job", 0, 1, "w", Lines("y", 3)).ok());
    absl::StatusOr<TaskLogPage> page = store->Read("job", 0, 0, 100);
    ASSERT_TRUE(page.ok());
    EXPECT_EQ(Texts(*page), (std::vector<std::string>{"... 2 earlier lines dropped", "x 2", "y 0",
                                                      "y 1", "y 2"}));
    EXPECT_EQ(page->lines[0].level, "warning");
    ASSERT_TRUE(store->Append("job", 0, 2, "w", Lines("z", 2)).ok());
    page = store->Read("job", 0, 0, 100);
    ASSERT_TRUE(page.ok());
    EXPECT_EQ(Texts(*page), (std::vector<std::string>{"... 4 earlier lines dropped", "y 1", "y 2",
                                                      "z 0", "z 1"}));
    // The other task's lines are not touched.
    EXPECT_EQ(Texts(*store->Read("job", 1, 0, 100)),
              (std::vector<std::string>{"other 0", "other 1"}));
}

TEST_F(TaskLogStoreTest, ATaskKeepsAtMostItsBytes) {
    auto store = Open({.max_lines_per_task = 1000, .max_bytes_per_task = 100});
    std::vector<TaskLogLine> lines = Lines("", 5);
    for (TaskLogLine& line : lines) line.text = std::string(30, 'a');
    ASSERT_TRUE(store->Append("job", 0, 1, "w", lines).ok());
    absl::StatusOr<TaskLogPage> page = store->Read("job", 0, 0, 100);
    ASSERT_TRUE(page.ok());
    ASSERT_EQ(page->lines.size(), 4u);  // 3 lines of 30 bytes fit in 100
    EXPECT_EQ(page->lines[0].text, "... 2 earlier lines dropped");
}

TEST_F(TaskLogStoreTest, WireLinesAreMadeSafeCutAndLevelled) {
    auto store = Open({.max_line_bytes = 16, .max_lines_per_message = 3});
    std::vector<TaskLogLine> lines = Lines("m", 5);
    lines[2].text = "forged\n[error] line\x1b[2J";
    lines[3].text = std::string(100, 'b');
    lines[4].level = "emergency";
    ASSERT_TRUE(store->Append("job", 0, 1, "w", lines).ok());
    absl::StatusOr<TaskLogPage> page = store->Read("job", 0, 0, 100);
    ASSERT_TRUE(page.ok());
    ASSERT_EQ(page->lines.size(), 4u);
    EXPECT_EQ(page->lines[0].text, "... 2 earlier lines dropped");
    EXPECT_EQ(page->lines[1].text.find('\n'), std::string::npos);
    EXPECT_EQ(page->lines[1].text.find('\x1b'), std::string::npos);
    EXPECT_EQ(page->lines[1].text.rfind("forged\\n", 0), 0u) << page->lines[1].text;
    EXPECT_LT(page->lines[2].text.size(), 40u);
    EXPECT_EQ(page->lines[2].text.rfind(std::string(16, 'b'), 0), 0u);
    EXPECT_EQ(page->lines[3].level, "info");
}

TEST_F(TaskLogStoreTest, LinesAndTaskListsSurviveAReopenAndGoWithTheirJob) {
    TaskStatus task;
    task.index = 1;
    task.state = TaskStatus::State::kDone;
    task.kind = TaskKind::kSplat;
    task.x = 8;
    task.width = 8;
    task.height = 4;
    task.samples = 16;
    task.attempts = 2;
    task.failures = 1;
    task.worker = "w2";
    task.leased = absl::FromUnixMillis(1'700'000'000'000);
    task.finished = absl::FromUnixMillis(1'700'000'002'500);
    task.duration = absl::Milliseconds(2500);
    task.last_error = "out of memory (worker w1)";
    TaskStatus never;  // never leased: its times stay unset
    {
        auto store = Open();
        ASSERT_TRUE(store->Append("job", 1, 2, "w2", Lines("kept", 2)).ok());
        ASSERT_TRUE(store->Append("gone", 0, 1, "w", Lines("x", 1)).ok());
        ASSERT_TRUE(store->RecordTasks("job", {never, task}).ok());
        ASSERT_TRUE(store->RecordTasks("gone", {never}).ok());
    }
    auto store = Open();
    EXPECT_EQ(Texts(*store->Read("job", std::nullopt, 0, 100)),
              (std::vector<std::string>{"kept 0", "kept 1"}));
    absl::StatusOr<std::vector<TaskStatus>> tasks = store->Tasks("job");
    ASSERT_TRUE(tasks.ok());
    ASSERT_EQ(tasks->size(), 2u);
    EXPECT_EQ((*tasks)[0].leased, absl::InfinitePast());
    const TaskStatus& read = (*tasks)[1];
    EXPECT_EQ(read.index, 1);
    EXPECT_EQ(read.state, TaskStatus::State::kDone);
    EXPECT_EQ(read.kind, TaskKind::kSplat);
    EXPECT_EQ(read.x, 8);
    EXPECT_EQ(read.width, 8);
    EXPECT_EQ(read.height, 4);
    EXPECT_EQ(read.samples, 16u);
    EXPECT_EQ(read.attempts, 2);
    EXPECT_EQ(read.failures, 1);
    EXPECT_EQ(read.worker, "w2");
    EXPECT_EQ(read.leased, task.leased);
    EXPECT_EQ(read.finished, task.finished);
    EXPECT_EQ(read.duration, task.duration);
    EXPECT_EQ(read.last_error, task.last_error);

    ASSERT_TRUE(store->Delete({"gone"}).ok());
    EXPECT_TRUE(store->Read("gone", std::nullopt, 0, 100)->lines.empty());
    EXPECT_TRUE(store->Tasks("gone")->empty());
    EXPECT_EQ(store->Read("job", std::nullopt, 0, 100)->lines.size(), 2u);
    EXPECT_EQ(store->Tasks("job")->size(), 2u);
}

// A shot's task names its frames, and an ended shot's `tasks` are read from here: they keep them,
// and their workers' times (issue 30's history).
TEST_F(TaskLogStoreTest, AnEndedShotsTasksKeepTheirFrames) {
    TaskStatus chunk;
    chunk.index = 0;
    chunk.frames = {1, 2};
    chunk.times = {1.5, 2.25};
    TaskStatus still;
    still.index = 1;
    {
        auto store = Open();
        ASSERT_TRUE(store->RecordTasks("shot", {chunk, still}).ok());
    }
    absl::StatusOr<std::vector<TaskStatus>> tasks = Open()->Tasks("shot");
    ASSERT_TRUE(tasks.ok()) << tasks.status();
    ASSERT_EQ(tasks->size(), 2u);
    EXPECT_EQ((*tasks)[0].frames, (std::vector<int>{1, 2}));
    EXPECT_EQ((*tasks)[0].times, (TaskTimes{1.5, 2.25}));
    EXPECT_TRUE((*tasks)[1].frames.empty());
    EXPECT_EQ((*tasks)[1].times, TaskTimes{});
}

// A store written before shots had no frames column: it opens, its rows read as stills', and a
// shot's tasks record into it.
TEST_F(TaskLogStoreTest, AStoreFromBeforeShotsGainsTheFramesColumn) {
    {
        sqlite3* db = nullptr;
        ASSERT_EQ(sqlite3_open((dir_ / "logs.db").c_str(), &db), SQLITE_OK);
        ASSERT_EQ(
            sqlite3_exec(db,
                         "CREATE TABLE tasks (job TEXT NOT NULL, task INTEGER NOT NULL,"
                         "  state TEXT NOT NULL, kind INTEGER NOT NULL, x INTEGER NOT NULL,"
                         "  y INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL,"
                         "  samples INTEGER NOT NULL, attempts INTEGER NOT NULL,"
                         "  failures INTEGER NOT NULL, worker TEXT NOT NULL,"
                         "  leased_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL,"
                         "  duration_ms INTEGER NOT NULL, last_error TEXT NOT NULL,"
                         "  PRIMARY KEY (job, task));"
                         "INSERT INTO tasks VALUES ('old', 0, 'done', 0, 0, 0, 8, 8, 4, 1, 0, 'w',"
                         "  0, 0, 0, '');",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
        sqlite3_close(db);
    }
    auto store = Open();
    ASSERT_TRUE(store);
    absl::StatusOr<std::vector<TaskStatus>> old = store->Tasks("old");
    ASSERT_TRUE(old.ok()) << old.status();
    ASSERT_EQ(old->size(), 1u);
    EXPECT_EQ((*old)[0].width, 8);
    EXPECT_TRUE((*old)[0].frames.empty());
    EXPECT_EQ((*old)[0].times, TaskTimes{});  // nor the history's times
    TaskStatus chunk;
    chunk.frames = {3, 4};
    chunk.times = {1, 2};
    ASSERT_TRUE(store->RecordTasks("shot", {chunk}).ok());
    EXPECT_EQ(store->Tasks("shot")->at(0).frames, (std::vector<int>{3, 4}));
    EXPECT_EQ(store->Tasks("shot")->at(0).times, (TaskTimes{1, 2}));
    EXPECT_TRUE(Open());  // and opens again, migrated
}

}  // namespace
}  // namespace lf
