// The worker's task log capture: lines go to the task running when they are logged, from any
// thread but an ignored one; each task's pending lines are bounded, the oldest dropped and
// counted.
#include "lf/worker/task_log_sink.h"

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <thread>

#include "absl/time/clock.h"

namespace lf {
namespace {

std::vector<std::string> Texts(const std::vector<TaskLogLine>& lines) {
    std::vector<std::string> texts;
    for (const TaskLogLine& line : lines) texts.push_back(line.text);
    return texts;
}

TEST(TaskLogSink, LinesGoToTheTaskRunningWhenTheyAreLogged) {
    auto sink = std::make_shared<TaskLogSink>();
    spdlog::logger logger("render", sink);
    logger.info("before any task");
    const std::shared_ptr<TaskLog> first = sink->Begin();
    logger.info("first {}", 1);
    std::thread([&] { logger.warn("from a kernel thread"); }).join();
    std::thread([&] {
        TaskLogSink::IgnoreThisThread();
        logger.info("the sender's line");
    }).join();
    const std::shared_ptr<TaskLog> second = sink->Begin();
    logger.error("second");
    sink->End();
    logger.info("between tasks");

    const std::vector<TaskLogLine> lines = first->Take();
    EXPECT_EQ(Texts(lines),
              (std::vector<std::string>{"[render] first 1", "[render] from a kernel thread"}));
    EXPECT_EQ(lines[0].level, "info");
    EXPECT_EQ(lines[1].level, "warning");
    EXPECT_LE(absl::Now() - lines[0].time, absl::Seconds(10));
    EXPECT_EQ(Texts(second->Take()), (std::vector<std::string>{"[render] second"}));
    EXPECT_TRUE(second->Take().empty());  // taken once
}

TEST(TaskLogSink, ATaskKeepsItsNewestLinesAndSaysHowManyWentBetweenTakes) {
    auto sink = std::make_shared<TaskLogSink>(
        TaskLogBounds{.max_lines = 3, .max_bytes = 1 << 20, .max_line_bytes = 100});
    spdlog::logger logger("w", sink);
    const std::shared_ptr<TaskLog> task = sink->Begin();
    for (int i = 0; i < 5; ++i) logger.info("line {}", i);
    std::vector<TaskLogLine> taken = task->Take();
    EXPECT_EQ(Texts(taken), (std::vector<std::string>{"... 2 lines dropped", "[w] line 2",
                                                      "[w] line 3", "[w] line 4"}));
    EXPECT_EQ(taken[0].level, "warning");
    logger.info("line 5");
    EXPECT_EQ(Texts(task->Take()), (std::vector<std::string>{"[w] line 5"}));
}

TEST(TaskLogSink, LongLinesAreCutAndBytesBounded) {
    auto sink = std::make_shared<TaskLogSink>(
        TaskLogBounds{.max_lines = 100, .max_bytes = 100, .max_line_bytes = 40});
    spdlog::logger logger("w", sink);
    const std::shared_ptr<TaskLog> task = sink->Begin();
    logger.info("{}", std::string(1000, 'x'));
    std::vector<TaskLogLine> taken = task->Take();
    ASSERT_EQ(taken.size(), 1u);
    EXPECT_EQ(taken[0].text.rfind("[w] " + std::string(36, 'x') + "...(", 0), 0u) << taken[0].text;
    for (int i = 0; i < 10; ++i) logger.info("{}", std::string(20, 'y'));  // 24 bytes each
    taken = task->Take();
    ASSERT_EQ(taken.size(), 5u);  // four fit in 100 bytes
    EXPECT_EQ(taken[0].text, "... 6 lines dropped");
}

}  // namespace
}  // namespace lf
