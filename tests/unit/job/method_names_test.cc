// Method names are compared in one place: the registry (lf/job/method_registry.h) and the CLI's
// flag parsing (client/src/*_flags.cc). Anywhere else a comparison with a method's name is a second
// registry that drifts; this test greps the source tree for them and lists each.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "lf/job/method_registry.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

bool Allowed(const fs::path& relative) {
    const std::string name = relative.filename().string();
    return relative == fs::path("job/src/method_registry.cc") ||
           (relative.parent_path() == fs::path("client/src") && name.ends_with("_flags.cc"));
}

TEST(MethodNames, AreComparedOnlyInTheRegistryAndTheFlagParsers) {
    std::string names = "auto";
    for (const MethodInfo& info : AllMethods()) names += "|" + std::string(info.name);
    const std::regex comparison("(==|!=)\\s*\"(" + names + ")\"|\"(" + names + ")\"\\s*(==|!=)");
    const fs::path root(LF_SOURCE_DIR);
    std::vector<std::string> found;
    int files = 0;
    for (const char* dir :
         {"core", "kernels", "job", "local", "server", "worker", "client", "wire"}) {
        for (const fs::directory_entry& entry : fs::recursive_directory_iterator(root / dir)) {
            const fs::path& path = entry.path();
            if (path.extension() != ".cc" && path.extension() != ".h") continue;
            ++files;
            const fs::path relative = fs::relative(path, root);
            if (Allowed(relative)) continue;
            std::ifstream in(path);
            std::string line;
            for (int number = 1; std::getline(in, line); ++number) {
                if (std::regex_search(line, comparison)) {
                    found.push_back(relative.string() + ":" + std::to_string(number) + ": " + line);
                }
            }
        }
    }
    EXPECT_GT(files, 100) << "no source tree at " << LF_SOURCE_DIR;
    std::string list;
    for (const std::string& f : found) list += "\n  " + f;
    EXPECT_TRUE(found.empty()) << "method names compared outside the registry (use "
                                  "lf::FindMethod, lf::Info, lf::MethodOf):"
                               << list;
}

}  // namespace
}  // namespace lf
