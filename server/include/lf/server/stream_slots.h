// Open streams of one kind (uploads, watches, result downloads) bounded farm-wide and per token:
// each holds one of the server's threads while it lasts, and one token's stalled streams must
// leave room for every other token's.
#pragma once

#include <mutex>
#include <string>
#include <unordered_map>

#include "absl/status/statusor.h"

namespace lf {

class StreamSlots {
  public:
    struct Limits {
        std::string what;  // "WatchJob streams", for the refusals
        int max = 0;       // farm-wide; 0: unbounded here
        std::string max_flag;
        int max_per_token = 0;  // 0: unbounded
        std::string per_token_flag;
        std::string hint;  // what the refused caller may do instead
    };
    explicit StreamSlots(Limits limits) : limits_(std::move(limits)) {}

    // A slot held until destroyed.
    class Slot {
      public:
        Slot(Slot&& other) noexcept : slots_(other.slots_), token_(std::move(other.token_)) {
            other.slots_ = nullptr;
        }
        Slot& operator=(Slot&&) = delete;
        ~Slot();

      private:
        friend class StreamSlots;
        Slot(StreamSlots* slots, std::string token) : slots_(slots), token_(std::move(token)) {}
        StreamSlots* slots_;
        std::string token_;
    };

    // A slot for a stream of the token named `token` ("" with authentication off: only the
    // farm-wide bound applies). ResourceExhausted naming the bound and its flag when the farm or
    // the token holds the most already.
    absl::StatusOr<Slot> Take(const std::string& token);

  private:
    void Release(const std::string& token);

    const Limits limits_;
    std::mutex mutex_;
    int open_ = 0;
    std::unordered_map<std::string, int> per_token_;
};

}  // namespace lf
