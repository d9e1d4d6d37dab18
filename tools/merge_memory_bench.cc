// Resident memory of merging one job on the coordinator: a plain job and an adaptive one merge
// synthetic tile results with their tiles in memory (as before tile files) and in a file
// (lf::MakeFileTileStore, as the coordinator now keeps them). Each case runs in a child process
// and prints its peak resident set (getrusage ru_maxrss) after merging and after one snapshot
// (the image a preview or result is written from), less the child's peak at its start.
//
//   build/bin/merge_memory_bench [--size 4096] [--tile 32] [--spp 2] [--dir /tmp]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <functional>
#include <string>

#include "lf/job/adaptive_plan.h"
#include "lf/job/merge.h"

namespace {

long PeakKb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}

lf::TileSums Result(const lf::RenderTask& task) {
    lf::TileSums sums(task.rect);
    for (size_t i = 0; i < sums.pixels.size(); ++i) {
        for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
            sums.pixels[i].Add(s, lf::Rgb(0.25f + float((i * 7 + s * 13) % 17) * 0.05f));
        }
    }
    return sums;
}

// Merges every task, growing with the plan, then snapshots; prints the figures per pixel.
void Run(const char* name, lf::TileMerger& merger, long start_kb) {
    for (size_t t = 0; t < merger.tasks().size(); ++t) {
        const lf::RenderTask task = merger.tasks()[t];
        if (absl::StatusOr<std::vector<lf::RenderTask>> s = merger.Merge(int(t), Result(task));
            !s.ok()) {
            std::fprintf(stderr, "%s: %s\n", name, std::string(s.status().message()).c_str());
            std::exit(1);
        }
    }
    const long merged_kb = PeakKb() - start_kb;
    absl::StatusOr<lf::Image> image = merger.Snapshot();
    if (!image.ok()) std::exit(1);
    const long snapshot_kb = PeakKb() - start_kb;
    const double pixels = double(merger.width()) * merger.height();
    std::printf(
        "%-18s %6zu tasks  merging %8.1f MB (%6.1f B/px)  +snapshot %8.1f MB (%6.1f B/px)\n", name,
        merger.tasks().size(), merged_kb / 1024.0, merged_kb * 1024.0 / pixels,
        snapshot_kb / 1024.0, snapshot_kb * 1024.0 / pixels);
    std::fflush(stdout);
}

void InChild(const std::function<void()>& body) {
    const pid_t pid = fork();
    if (pid == 0) {
        body();
        std::_Exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"peak resident memory of merging a job, tiles in memory or in a file"};
    int size = 4096, tile = 32;
    uint64_t spp = 2;
    std::string dir = "/tmp";
    app.add_option("--size", size, "image width and height")->capture_default_str();
    app.add_option("--tile", tile, "tile side")->capture_default_str();
    app.add_option("--spp", spp, "samples per pixel (adaptive: of the first pass; up to 2x)")
        ->capture_default_str();
    app.add_option("--dir", dir, "folder of the tile files")->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    const lf::TileStoreFactory in_file = [&](std::vector<lf::PixelRect> tiles, uint32_t aovs) {
        return lf::MakeFileTileStore(dir, std::move(tiles), aovs);
    };
    std::printf("%dx%d, %d px tiles, %llu spp\n", size, size, tile, (unsigned long long)spp);
    std::fflush(stdout);  // not again by each child
    for (const bool file : {false, true}) {
        const lf::TileStoreFactory stores =
            file ? in_file : lf::TileStoreFactory(lf::MakeMemoryTileStore);
        InChild([&] {
            const long start = PeakKb();
            absl::StatusOr<std::vector<lf::RenderTask>> plan =
                lf::PlanRender({size, size, spp, tile, 1});
            absl::StatusOr<std::unique_ptr<lf::RenderMerger>> merger =
                lf::RenderMerger::Make(size, size, *plan, stores);
            if (!merger.ok()) std::exit(1);
            Run(file ? "plain, file" : "plain, memory", **merger, start);
        });
        InChild([&] {
            const long start = PeakKb();
            // A target no tile reaches: every tile takes a second pass, up to 2x the first.
            const lf::AdaptiveSettings settings{1e-9, 0, 2 * spp};
            absl::StatusOr<std::unique_ptr<lf::AdaptiveTilePlan>> plan = lf::AdaptiveTilePlan::Make(
                size, size, spp, tile, settings, lf::kMaxTaskSamples, stores);
            if (!plan.ok()) std::exit(1);
            Run(file ? "adaptive, file" : "adaptive, memory", **plan, start);
        });
    }
    return 0;
}
