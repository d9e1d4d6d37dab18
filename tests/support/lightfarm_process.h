// Runs the built `lightfarm` binary (LF_BIN_DIR) as a user would, for tests of the CLI.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace lf::testing {

struct LightfarmRun {
    int status;          // the exit status
    std::string output;  // stdout and stderr
};

// `lightfarm ARGS` through the shell (ARGS may quote).
inline LightfarmRun RunLightfarm(const std::string& args) {
    const std::string cmd = std::string(LF_BIN_DIR) + "/lightfarm " + args + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    return {WEXITSTATUS(pclose(pipe)), out};
}

}  // namespace lf::testing
