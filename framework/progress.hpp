#pragma once
// A live progress line on stderr (trials done/total, elapsed, ETA), drawn only when stderr is a
// terminal so logs and CI output stay clean.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>

namespace mhb {

class ProgressLine {
public:
    ProgressLine(std::size_t total, bool enabled);
    ~ProgressLine();
    void advance();  // thread-safe; one finished item
    void finish();
    static bool stderr_is_terminal();

private:
    void draw(std::size_t done, bool final);
    std::size_t total_;
    bool enabled_;
    std::atomic<std::size_t> done_{0};
    std::chrono::steady_clock::time_point start_, last_draw_;
    std::mutex mutex_;
    bool finished_ = false;
};

}  // namespace mhb
