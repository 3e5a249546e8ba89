#include "framework/progress.hpp"

#include <cstdio>

#include <unistd.h>

namespace mhb {

ProgressLine::ProgressLine(std::size_t total, bool enabled)
    : total_(total), enabled_(enabled && total > 0), start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

ProgressLine::~ProgressLine() { finish(); }

bool ProgressLine::stderr_is_terminal() { return isatty(STDERR_FILENO) == 1; }

void ProgressLine::advance() {
    const std::size_t done = ++done_;
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    draw(done, false);
}

void ProgressLine::finish() {
    std::lock_guard lock(mutex_);
    if (!enabled_ || finished_) return;
    finished_ = true;
    draw(done_, true);
}

void ProgressLine::draw(std::size_t done, bool final) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double eta = done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(total_ - done) : 0.0;
    std::fprintf(stderr, "\r  trials %zu/%zu (%3.0f%%)  elapsed %.1f s  ETA %.1f s   ", done, total_,
                 100.0 * static_cast<double>(done) / static_cast<double>(total_), elapsed, eta);
    if (final) std::fputc('\n', stderr);
    std::fflush(stderr);
}

}  // namespace mhb
