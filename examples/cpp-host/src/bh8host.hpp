// bh8host: a tiny C++ host library for a Barrett BH8 hand on a serial port (an example for
// the gcl CTest recipe in ../CMakeLists.txt). Every read has a deadline; whatever the hand
// does wrong is a bh8::Error.
#pragma once

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

namespace bh8 {

struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Hand {
public:
    // Opens a serial device (or a pty) raw, at `baud`.
    explicit Hand(const std::string& path, int baud = 9600,
                  std::chrono::milliseconds timeout = std::chrono::milliseconds(1000));
    ~Hand();
    Hand(const Hand&) = delete;
    Hand& operator=(const Hand&) = delete;

    // ^C, then everything up to the prompt is dropped.
    void sync();
    // Sends one command line (ended by a single CR); returns the answer's lines between the
    // echo and the prompt. `ERR n` is an Error.
    std::vector<std::string> command(const std::string& line);
    std::string version();
    void home();
    std::vector<long> get(const std::string& param, const std::string& motors = "");

private:
    std::string read_until(const std::string& end);
    void write_all(const std::string& bytes);
    int fd_;
    std::chrono::milliseconds timeout_;
};

}  // namespace bh8
