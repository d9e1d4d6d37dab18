// The plain rules of job dependencies (lf/server/job_dependencies.h): id checks, which states
// refuse a new dependency or fail a dependent, the waiting reason, and the cycle search.
#include "lf/server/job_dependencies.h"

#include <gtest/gtest.h>

#include <map>

namespace lf {
namespace {

TEST(JobDependencies, IdsCollapseAndAreBounded) {
    absl::StatusOr<std::vector<std::string>> ids = CheckDependencyIds({"a", "b", "a"}, "--after");
    ASSERT_TRUE(ids.ok()) << ids.status();
    EXPECT_EQ(*ids, (std::vector<std::string>{"a", "b"}));
    ids = CheckDependencyIds({"a", "c"}, "after", {"a", "b"});
    ASSERT_TRUE(ids.ok()) << ids.status();
    EXPECT_EQ(*ids, (std::vector<std::string>{"c"})) << "those the job has already are left out";

    const absl::Status empty = CheckDependencyIds({""}, "--after").status();
    EXPECT_TRUE(absl::IsInvalidArgument(empty)) << empty;
    EXPECT_NE(empty.message().find("--after"), std::string::npos) << empty;
    const absl::Status long_id =
        CheckDependencyIds({std::string(kMaxDependencyIdBytes + 1, 'x')}, "--after").status();
    EXPECT_TRUE(absl::IsInvalidArgument(long_id)) << long_id;

    std::vector<std::string> many;
    for (size_t i = 0; i < kMaxDependencies; ++i) many.push_back("job-" + std::to_string(i));
    EXPECT_TRUE(CheckDependencyIds(many, "after").ok());
    many.push_back(many.front());
    EXPECT_TRUE(CheckDependencyIds(many, "after").ok()) << "a repeat is no extra dependency";
    many.push_back("job-extra");
    const absl::Status over = CheckDependencyIds(many, "after").status();
    EXPECT_TRUE(absl::IsInvalidArgument(over)) << over;
    EXPECT_NE(over.message().find("65"), std::string::npos) << over;
    EXPECT_FALSE(CheckDependencyIds({"job-extra"}, "after",
                                    std::vector<std::string>(many.begin(), many.begin() + 64))
                     .ok())
        << "counted with those the job has";
}

TEST(JobDependencies, NewDependencyMustBeKnownAndNotFailed) {
    const absl::Status unknown = CheckNewDependency({"job-x"});
    EXPECT_TRUE(absl::IsNotFound(unknown)) << unknown;
    EXPECT_NE(unknown.message().find("job-x"), std::string::npos) << unknown;
    for (JobState s : {JobState::kFailed, JobState::kCancelled}) {
        const absl::Status ended = CheckNewDependency({"job-y", s});
        EXPECT_TRUE(absl::IsFailedPrecondition(ended)) << ended;
        EXPECT_NE(ended.message().find("job-y"), std::string::npos) << ended;
        EXPECT_NE(ended.message().find(JobStateName(s)), std::string::npos) << ended;
    }
    for (JobState s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded}) {
        EXPECT_TRUE(CheckNewDependency({"job-z", s}).ok()) << JobStateName(s);
    }
}

TEST(JobDependencies, FailureReasons) {
    EXPECT_EQ(DependencyFailure({"job-a", JobState::kFailed, "task 3 failed"}),
              "dependency job-a failed: task 3 failed");
    EXPECT_EQ(DependencyFailure({"job-a", JobState::kCancelled}), "dependency job-a was cancelled");
    EXPECT_EQ(DependencyFailure({"job-a"}), std::nullopt)
        << "a job gone was deleted once ended, its dependents settled then";
    for (JobState s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded}) {
        EXPECT_EQ(DependencyFailure({"job-a", s}), std::nullopt) << JobStateName(s);
    }
}

TEST(JobDependencies, WaitingReasonNamesEachJobAndItsState) {
    EXPECT_EQ(WaitingForDependencies({{"job-1", JobState::kRunning}, {"job-2", JobState::kQueued}}),
              "waiting for job-1 (running), job-2 (queued)");
}

TEST(JobDependencies, CycleSearchFollowsTheWaitingJobs) {
    // B runs after A, C after B; A ended (runs after nothing any more).
    const std::map<std::string, std::vector<std::string>> graph = {
        {"B", {"A"}}, {"C", {"B"}}, {"D", {"C", "B"}}};
    const DependenciesOf after_of = [&](const std::string& id) {
        auto it = graph.find(id);
        return it == graph.end() ? std::vector<std::string>{} : it->second;
    };
    EXPECT_EQ(FindCycle("E", {"C", "D"}, after_of), std::nullopt) << "nothing waits for E";
    EXPECT_EQ(FindCycle("A", {"C"}, after_of), (std::vector<std::string>{"A", "C", "B", "A"}));
    EXPECT_EQ(FindCycle("D", {"A"}, after_of), std::nullopt);
    const std::optional<std::vector<std::string>> cycle = FindCycle("B", {"A", "D"}, after_of);
    ASSERT_TRUE(cycle.has_value());
    EXPECT_EQ(CycleText(*cycle), "cycle: B -> D -> C -> B");
    EXPECT_EQ(FindCycle("A", {"A"}, after_of), (std::vector<std::string>{"A", "A"}));
}

}  // namespace
}  // namespace lf
