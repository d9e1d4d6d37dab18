// The "scene" logger's output in a string a test can search (the loader's warnings).
#pragma once

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>

namespace lf::testing {

inline std::ostringstream& CapturedSceneLog() {
    static std::ostringstream* const log = [] {
        auto* stream = new std::ostringstream;
        spdlog::drop("scene");
        spdlog::register_logger(std::make_shared<spdlog::logger>(
            "scene", std::make_shared<spdlog::sinks::ostream_sink_mt>(*stream)));
        return stream;
    }();
    return *log;
}

}  // namespace lf::testing
