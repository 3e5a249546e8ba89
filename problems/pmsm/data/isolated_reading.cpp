// A reader run in a child process, so that a fault inside libhdf5 on a damaged file (fuzz_hdf5 found
// a global-heap object whose declared size makes H5HG_read copy past its buffer: a segfault in
// every release of the program) becomes a refusal naming the file, not the end of a run that may
// have hours of trials behind it. The child reads, bounded in memory and time, and hands back the
// columns (or its refusal) through a pipe; the parent checks what it receives.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define MHBENCH_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MHBENCH_ADDRESS_SANITIZER 1
#endif
#endif

namespace mhb::pmsm {
namespace {

// What the child may take beyond the parent's address space: the largest measurement (5 million
// rows of ten columns, 400 MB) read and encoded, with room for the library.
constexpr std::uint64_t child_memory_bytes = std::uint64_t{3} << 30;

class Encoder {
public:
    void number(std::uint64_t v) { bytes(&v, sizeof v); }
    void text(const std::string& s) {
        number(s.size());
        bytes(s.data(), s.size());
    }
    void bytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
    const std::string& out() const { return out_; }

private:
    std::string out_;
};

// Reads back what Encoder wrote; anything short or out of range is the child's failure.
class Decoder {
public:
    Decoder(const std::string& in, const std::string& file) : in_(in), file_(file) {}
    std::uint64_t number() {
        std::uint64_t v;
        bytes(&v, sizeof v);
        return v;
    }
    std::uint64_t count(std::uint64_t most) {
        const auto n = number();
        if (n > most) broken();
        return n;
    }
    std::string text() {
        std::string s(count(left()), '\0');
        bytes(s.data(), s.size());
        return s;
    }
    void bytes(void* p, std::size_t n) {
        if (n > left()) broken();
        std::memcpy(p, in_.data() + at_, n);
        at_ += n;
    }
    std::size_t left() const { return in_.size() - at_; }
    [[noreturn]] void broken() const { throw InputError(file_, 0, "", "the reading process handed back broken columns (an mhbench bug)"); }

private:
    const std::string& in_;
    const std::string& file_;
    std::size_t at_ = 0;
};

std::string encoded(const FileColumns& c) {
    Encoder e;
    e.number(0);
    e.number(c.columns.size());
    for (const auto& column : c.columns) {
        e.text(column.name);
        e.text(column.column);
        e.number(column.labels ? 1 : 0);
        if (column.labels) {
            e.number(column.labels->texts.size());
            for (const auto& t : column.labels->texts) e.text(t);
            e.number(static_cast<std::uint64_t>(column.labels->rows.size()));
            e.bytes(column.labels->rows.data(), static_cast<std::size_t>(column.labels->rows.size()) * sizeof(int));
        } else {
            e.number(static_cast<std::uint64_t>(column.numbers.size()));
            e.bytes(column.numbers.data(), static_cast<std::size_t>(column.numbers.size()) * sizeof(double));
        }
    }
    for (const auto* list : {&c.unused, &c.notes}) {
        e.number(list->size());
        for (const auto& s : *list) e.text(s);
    }
    return e.out();
}

std::string encoded(const InputError& error) {
    Encoder e;
    e.number(1);
    e.text(error.file());
    e.number(static_cast<std::uint64_t>(error.line()));
    e.text(error.field());
    e.text(error.message());
    return e.out();
}

FileColumns decoded(const std::string& in, const std::string& file) {
    Decoder d(in, file);
    const auto kind = d.number();
    if (kind == 1) {
        std::string f = d.text();
        const auto line = static_cast<long>(d.number());
        std::string field = d.text();
        throw InputError(std::move(f), line, std::move(field), d.text());
    }
    if (kind != 0) d.broken();
    FileColumns c;
    const auto rows_at_most = static_cast<std::uint64_t>(max_measurement_rows);
    for (auto n = d.count(max_file_variables); n > 0; --n) {
        FileColumn& column = c.columns.emplace_back();
        column.name = d.text();
        column.column = d.text();
        if (d.number() == 1) {
            TextColumn& labels = column.labels.emplace();
            for (auto t = d.count(rows_at_most); t > 0; --t) labels.texts.push_back(d.text());
            const auto rows = d.count(rows_at_most);
            labels.rows.resize(static_cast<Eigen::Index>(rows));
            d.bytes(labels.rows.data(), rows * sizeof(int));
            for (Eigen::Index r = 0; r < labels.rows.size(); ++r)
                if (labels.rows[r] < 0 || static_cast<std::size_t>(labels.rows[r]) >= labels.texts.size()) d.broken();
            // The index is not handed over: only the reader adds texts to it.
        } else {
            const auto rows = d.count(rows_at_most);
            column.numbers.resize(static_cast<Eigen::Index>(rows));
            d.bytes(column.numbers.data(), rows * sizeof(double));
        }
    }
    for (auto* list : {&c.unused, &c.notes})
        for (auto n = d.count(max_file_variables); n > 0; --n) list->push_back(d.text());
    if (d.left() != 0) d.broken();
    return c;
}

void write_all(int fd, const std::string& bytes) {
    for (std::size_t at = 0; at < bytes.size();) {
        const ssize_t n = ::write(fd, bytes.data() + at, bytes.size() - at);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        at += static_cast<std::size_t>(n);
    }
}

// The child's side: read, encode, write, and leave without running the parent's exit handlers.
[[noreturn]] void run_child(int fd, const std::string& file, const std::function<FileColumns()>& read, unsigned seconds) {
    alarm(seconds);
#ifndef MHBENCH_ADDRESS_SANITIZER
    // AddressSanitizer reserves terabytes of address space for its shadow; a limit would stop it.
    long pages = 0;
    if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
        std::fclose(statm);
    }
    const auto limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) + child_memory_bytes;
    const rlimit memory{limit, limit};
    setrlimit(RLIMIT_AS, &memory);
#endif
    std::string out;
    try {
        out = encoded(read());
    } catch (const InputError& e) {
        out = encoded(e);
    } catch (const std::bad_alloc&) {
        out = encoded(InputError(file, 0, "", fmt::format("reading it needs more than {} MB of memory; the file is damaged or not a "
                                                          "measurement", child_memory_bytes >> 20)));
    } catch (const std::exception& e) {
        out = encoded(InputError(file, 0, "", e.what()));
    }
    write_all(fd, out);
    _exit(0);
}

}  // namespace

FileColumns read_in_child_process(const std::string& file, const std::string& library, const std::function<FileColumns()>& read,
                                  unsigned seconds) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw InputError(file, 0, "", fmt::format("cannot start reading it: {}", std::strerror(errno)));
    // The parent may run other threads (trials); the child is a copy of this thread alone and calls
    // only the reader, libhdf5 and malloc, whose locks glibc resets for a child at fork.
    const pid_t child = fork();
    if (child < 0) {
        close(fds[0]);
        close(fds[1]);
        throw InputError(file, 0, "", fmt::format("cannot start reading it: {}", std::strerror(errno)));
    }
    if (child == 0) {
        close(fds[0]);
        run_child(fds[1], file, read, seconds);
    }
    close(fds[1]);
    std::string in;
    char block[1 << 16];
    while (true) {
        const ssize_t n = ::read(fds[0], block, sizeof block);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        in.append(block, static_cast<std::size_t>(n));
    }
    close(fds[0]);
    int status = 0;
    while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFSIGNALED(status)) {
        const int signal = WTERMSIG(status);
        if (signal == SIGALRM)
            throw InputError(file, 0, "", fmt::format("reading it took over {} s and was stopped ({} looping on a damaged file?)", seconds, library));
        throw InputError(file, 0, "",
                         fmt::format("{} failed on it ({}, in the process that reads the file); the file is damaged or not what it "
                                     "claims to be (save or copy it again)",
                                     library, strsignal(signal)));
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || in.empty())
        throw InputError(file, 0, "", fmt::format("the process reading it ended without an answer ({} on a damaged file?)", library));
    return decoded(in, file);
}

}  // namespace mhb::pmsm
