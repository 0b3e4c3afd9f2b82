// BUG: a C++ host whose port class throws std::system_error when a read or write fails
// (the hand hung up: EIO on a pty, a reset on TCP) and that never catches it, as a ROS node
// on Boost.Asio did (`terminate called after throwing an instance of
// 'boost::wrapexcept<boost::system::system_error>' what(): write: Input/output error`).
// Every read has a deadline; a timeout is reported and the host exits 1.
// Expected finding: one crash, `crash: SIGABRT: uncaught C++ exception std::system_error`,
// with what() in its message; built with AddressSanitizer (its SIGABRT handler prints the
// stack), `... thrown in Port::check` (the host's own frame that threw).
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <poll.h>
#include <stdexcept>
#include <string>
#include <system_error>
#include <termios.h>
#include <unistd.h>

// The host's own error for a hand that does not answer in time, which it handles.
struct Timeout : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Port {
  public:
    explicit Port(const char *path) : fd_(open(path, O_RDWR | O_NOCTTY)) {
        check(fd_, "open");
        termios t{};
        tcgetattr(fd_, &t);
        cfmakeraw(&t);
        tcsetattr(fd_, TCSANOW, &t);
    }
    ~Port() { close(fd_); }

    void write_bytes(const std::string &bytes) {
        check(static_cast<int>(::write(fd_, bytes.data(), bytes.size())), "write");
    }

    // Everything up to and including the prompt; throws Timeout after 1 s of silence.
    std::string read_answer() {
        std::string got;
        while (got.size() < 3 || got.compare(got.size() - 3, 3, "=> ") != 0) {
            pollfd p{fd_, POLLIN, 0};
            if (poll(&p, 1, 1000) <= 0) throw Timeout("no prompt after " + got);
            char c;
            ssize_t n = ::read(fd_, &c, 1);
            if (n == 0) errno = EIO;
            check(n == 1 ? 1 : -1, "read");
            got += c;
        }
        return got;
    }

  private:
    // The bug's home: a failed call becomes an exception nobody catches.
    static void check(int r, const char *what) {
        if (r < 0) throw std::system_error(errno, std::generic_category(), what);
    }
    int fd_;
};

static const char *scenario[] = {"HI", "FGET DP", "1M 5000", "1FGET P", "C", "O", "FGET P", "2M 1000", "123FGET P"};

int main(int argc, char **argv) {
    const char *path = argc > 1 ? argv[1] : getenv("GCL_PORT");
    if (!path) return 2;
    Port port(path);
    try {
        port.write_bytes("\x03");
        port.read_answer();
        for (const char *line : scenario) {
            port.write_bytes(std::string(line) + "\r");
            if (port.read_answer().find("ERR") != std::string::npos) {
                std::fprintf(stderr, "host: %s refused\n", line);
                return 1;
            }
        }
    } catch (const Timeout &e) {
        // Timeouts are handled; a failed read or write (std::system_error) is not.
        std::fprintf(stderr, "host: %s\n", e.what());
        return 1;
    }
    return 0;
}
