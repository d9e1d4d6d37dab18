// `lightfarm-server token`: what it tells the operator. The first token turns authentication on
// for every caller, running workers included: it says so, and what the workers need. `rotate`
// gives a name a new token and refuses the old one.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "absl/strings/match.h"
#include "lf/server/token_store.h"
#include "test_dir.h"

namespace lf {
namespace {

struct Output {
    int status = -1;
    std::string text;  // stdout and stderr
    std::string last_line;
};

Output Token(const std::string& args) {
    const std::string command =
        std::string(LF_BIN_DIR) + "/lightfarm-server token " + args + " 2>&1";
    Output out;
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return out;
    char buffer[4096];
    for (size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.text.append(buffer, n);
    const int status = pclose(pipe);
    out.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::string text = out.text;
    while (!text.empty() && text.back() == '\n') text.pop_back();
    out.last_line = text.substr(text.rfind('\n') + 1);
    return out;
}

TEST(TokenCommand, FirstTokenWarnsThatWorkersNowNeedOne) {
    const std::string dir = testing::FreshTestDir("lf_token_cmd").string();
    const Output first = Token("create --data-dir " + dir + " --name alice --role submitter");
    ASSERT_EQ(first.status, 0) << first.text;
    EXPECT_TRUE(absl::StrContains(first.text, "first token")) << first.text;
    EXPECT_TRUE(absl::StrContains(first.text, "--role worker")) << first.text;
    EXPECT_TRUE(absl::StrContains(first.text, "--token-file")) << first.text;
    EXPECT_TRUE(absl::StartsWith(first.last_line, "lf1_")) << first.text;

    const Output second = Token("create --data-dir " + dir + " --name node1 --role worker");
    ASSERT_EQ(second.status, 0) << second.text;
    EXPECT_FALSE(absl::StrContains(second.text, "first token")) << second.text;
}

TEST(TokenCommand, RotatePrintsANewTokenForTheSameNameAndRefusesTheOld) {
    const std::string dir = testing::FreshTestDir("lf_token_cmd").string();
    const Output made = Token("create --data-dir " + dir + " --name bob --role submitter");
    ASSERT_EQ(made.status, 0) << made.text;
    const Output rotated = Token("rotate --data-dir " + dir + " --name bob");
    ASSERT_EQ(rotated.status, 0) << rotated.text;
    ASSERT_TRUE(absl::StartsWith(rotated.last_line, "lf1_")) << rotated.text;
    EXPECT_NE(rotated.last_line, made.last_line);

    auto store = TokenStore::Open(dir);
    ASSERT_TRUE(store.ok()) << store.status();
    EXPECT_FALSE((*(*store)->Find(made.last_line))->valid());
    auto now = *(*store)->Find(rotated.last_line);
    ASSERT_TRUE(now.has_value());
    EXPECT_TRUE(now->valid());
    EXPECT_EQ(now->name, "bob");

    const Output unknown = Token("rotate --data-dir " + dir + " --name nobody");
    EXPECT_EQ(unknown.status, 1);
    EXPECT_TRUE(absl::StrContains(unknown.text, "no token named \"nobody\"")) << unknown.text;
}

}  // namespace
}  // namespace lf
