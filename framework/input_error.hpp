#pragma once
// Errors in what a user hands us (configs, data files, command-line values). Each names where the
// problem is, so the CLI can print one line such as
//   error: experiments/demo.toml:12: optimizer.population: must be an even integer >= 4 (got 7)
// and exit with code 2.
#include <stdexcept>
#include <string>

namespace mhb {

class InputError : public std::runtime_error {
public:
    InputError(std::string file, long line, std::string field, std::string message)
        : std::runtime_error(format(file, line, field, message)),
          file_(std::move(file)), line_(line), field_(std::move(field)), message_(std::move(message)) {}

    const std::string& file() const { return file_; }
    long line() const { return line_; }  // 0 when no line applies
    const std::string& field() const { return field_; }
    const std::string& message() const { return message_; }

private:
    static std::string format(const std::string& file, long line, const std::string& field,
                              const std::string& message) {
        std::string out = file.empty() ? std::string("<input>") : file;
        if (line > 0) out += ":" + std::to_string(line);
        out += ": ";
        if (!field.empty()) out += field + ": ";
        return out + message;
    }
    std::string file_;
    long line_;
    std::string field_;
    std::string message_;
};

// A value that breaks a parameter's declared type or range; the caller knows the file and line and
// rethrows it as an InputError.
class ParameterError : public std::runtime_error {
public:
    ParameterError(std::string field, const std::string& message)
        : std::runtime_error(field + ": " + message), field_(std::move(field)), message_(message) {}
    const std::string& field() const { return field_; }
    const std::string& message() const { return message_; }

private:
    std::string field_;
    std::string message_;
};

// A fault inside a plugin during a trial (a NaN fitness, a candidate outside the box, an exception):
// it fails that trial only.
class PluginFault : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace mhb
