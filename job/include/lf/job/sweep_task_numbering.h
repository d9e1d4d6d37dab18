// Where a radiosity job's patch-group tasks sit among its tasks: after the job's `tiles` tile
// tasks, sweep k's chunk c is task tiles + k * chunks + c, so a sweep's tasks are appended in
// order once the sweep before it is solved.
#pragma once

#include <optional>

namespace lf {

struct SweepTaskNumbering {
    int tiles = 0;   // tile tasks, numbered first
    int chunks = 1;  // patch-group tasks per sweep

    struct SweepChunk {
        int sweep = 0;
        int chunk = 0;
        bool operator==(const SweepChunk&) const = default;
    };

    int ToIndex(SweepChunk at) const { return tiles + at.sweep * chunks + at.chunk; }
    // The sweep and chunk of task `index`; nullopt for a tile's task.
    std::optional<SweepChunk> FromIndex(int index) const {
        if (index < tiles) return std::nullopt;
        return SweepChunk{(index - tiles) / chunks, (index - tiles) % chunks};
    }
};

}  // namespace lf
