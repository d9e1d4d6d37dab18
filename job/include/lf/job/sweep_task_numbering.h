// Where a radiosity job's sweep tasks sit among its tasks: after the job's `tiles` tile tasks,
// each sweep's tasks in turn, appended once the sweep before it is solved. A task covers one or
// more patch-group chunks: sweep 0 one a chunk, a later sweep one a worker holding chunks
// (lf::SweepExecution), so a sweep's task count is known only when it starts.
#pragma once

#include <algorithm>
#include <optional>
#include <span>
#include <vector>

namespace lf {

class SweepTaskNumbering {
  public:
    explicit SweepTaskNumbering(int tiles) : end_(tiles) {}

    // Numbers the next sweep's tasks, each the chunks it covers; returns their indices.
    std::vector<int> Append(std::vector<std::vector<int>> task_chunks) {
        std::vector<int> indices;
        for (size_t k = 0; k < task_chunks.size(); ++k) indices.push_back(end_ + int(k));
        sweeps_.push_back({end_, std::move(task_chunks)});
        end_ += int(sweeps_.back().tasks.size());
        return indices;
    }

    struct SweepTask {
        int sweep = 0;
        std::span<const int> chunks;
    };
    // The sweep and chunks of task `index`; nullopt for a tile's task or one not numbered. The
    // chunks stay valid while the numbering lives (Append moves a task's chunk list, not its
    // buffer).
    std::optional<SweepTask> FromIndex(int index) const {
        auto after = std::upper_bound(sweeps_.begin(), sweeps_.end(), index,
                                      [](int i, const Sweep& s) { return i < s.first; });
        if (after == sweeps_.begin() || index >= end_) return std::nullopt;
        const Sweep& s = *(after - 1);
        return SweepTask{int(after - 1 - sweeps_.begin()), s.tasks[size_t(index - s.first)]};
    }
    int sweeps() const { return int(sweeps_.size()); }
    int end() const { return end_; }  // one past the last task numbered

  private:
    struct Sweep {
        int first;  // the index of its first task
        std::vector<std::vector<int>> tasks;
    };
    std::vector<Sweep> sweeps_;
    int end_;
};

}  // namespace lf
