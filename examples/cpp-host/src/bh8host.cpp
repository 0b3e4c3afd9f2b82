#include "bh8host.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <poll.h>
#include <sstream>
#include <termios.h>
#include <unistd.h>

namespace bh8 {

namespace {
const std::string kPrompt = "=> ";
#ifdef BH8HOST_PLANTED_LF
// A planted bug (-DBH8HOST_PLANTED_LF=ON), for showing that the CTest fails: lines end in CR LF.
const std::string kLineEnd = "\r\n";
#else
// GCL: a command line ends in a single CR.
const std::string kLineEnd = "\r";
#endif
const std::string kEol = "\n\r";
// The longest answer kept: a hand that floods is an Error, not unbounded memory.
const size_t kMaxAnswer = 64 * 1024;

speed_t speed_of(int baud) {
    switch (baud) {
        case 9600: return B9600;
        case 19200: return B19200;
        case 38400: return B38400;
        case 57600: return B57600;
        case 115200: return B115200;
        default: throw Error("unsupported baud " + std::to_string(baud));
    }
}
}  // namespace

Hand::Hand(const std::string& path, int baud, std::chrono::milliseconds timeout)
    : fd_(::open(path.c_str(), O_RDWR | O_NOCTTY)), timeout_(timeout) {
    if (fd_ < 0) throw Error("cannot open " + path + ": " + std::strerror(errno));
    termios t{};
    if (tcgetattr(fd_, &t) == 0) {
        cfmakeraw(&t);
        cfsetispeed(&t, speed_of(baud));
        cfsetospeed(&t, speed_of(baud));
        tcsetattr(fd_, TCSANOW, &t);
    }
}

Hand::~Hand() {
    if (fd_ >= 0) ::close(fd_);
}

void Hand::write_all(const std::string& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
        ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw Error(std::string("write: ") + std::strerror(errno));
        done += static_cast<size_t>(n);
    }
}

std::string Hand::read_until(const std::string& end) {
    std::string buf;
    auto deadline = std::chrono::steady_clock::now() + timeout_;
    while (buf.size() < end.size() || buf.compare(buf.size() - end.size(), end.size(), end) != 0) {
        auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) throw Error("no answer ending in '" + end + "' in time");
        pollfd p{fd_, POLLIN, 0};
        int r = ::poll(&p, 1, static_cast<int>(left.count()));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) continue;
        char chunk[256];
        ssize_t n = ::read(fd_, chunk, sizeof chunk);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw Error("the line closed");
        buf.append(chunk, static_cast<size_t>(n));
        if (buf.size() > kMaxAnswer) throw Error("an answer longer than 64 KiB");
    }
    return buf;
}

void Hand::sync() {
    write_all("\x03");
    read_until(kPrompt);
}

std::vector<std::string> Hand::command(const std::string& line) {
    write_all(line + kLineEnd);
    std::string answer = read_until(kPrompt);
    answer.resize(answer.size() - kPrompt.size());
    std::vector<std::string> parts;
    size_t pos = 0;
    for (;;) {
        size_t at = answer.find(kEol, pos);
        parts.push_back(answer.substr(pos, at == std::string::npos ? std::string::npos : at - pos));
        if (at == std::string::npos) break;
        pos = at + kEol.size();
    }
    if (parts.empty() || parts[0] != line) throw Error("the hand echoed something else for " + line);
    std::vector<std::string> lines;
    for (size_t i = 1; i < parts.size(); ++i)
        if (!parts[i].empty()) lines.push_back(parts[i]);
    if (!lines.empty() && lines.back().rfind("ERR", 0) == 0) throw Error(line + " refused: " + lines.back());
    return lines;
}

std::string Hand::version() {
    auto lines = command("VERS");
    if (lines.empty()) throw Error("VERS answered nothing");
    return lines[0];
}

void Hand::home() { command("HI"); }

std::vector<long> Hand::get(const std::string& param, const std::string& motors) {
    std::vector<long> values;
    for (const auto& l : command(motors + "FGET " + param)) {
        std::istringstream in(l);
        std::string word;
        while (in >> word) {
            char* end = nullptr;
            errno = 0;
            long v = std::strtol(word.c_str(), &end, 10);
            if (end == word.c_str() || *end != '\0' || errno != 0) throw Error("not a number: " + word);
            values.push_back(v);
        }
    }
    return values;
}

}  // namespace bh8
