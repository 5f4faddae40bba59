#include "io/util/isolate.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include "core/errors.h"

namespace normalflow {

namespace {

// First byte of the child's message.
constexpr char kResult = 'R';
constexpr char kInvalidInput = 'I';
constexpr char kIoError = 'O';
constexpr char kNumericalError = 'N';
constexpr char kCancelled = 'C';
constexpr char kOutOfMemory = 'M';
constexpr char kOther = 'X';

/// Closes a file descriptor once.
struct Fd {
    int fd = -1;
    Fd() = default;
    explicit Fd(int f) : fd(f) {}
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    ~Fd() { reset(); }
    void reset() {
        if (fd >= 0) ::close(fd);
        fd = -1;
    }
};

/// Kills (SIGKILL) and reaps the child unless it was reaped already: no zombie on any path.
struct Child {
    pid_t pid = -1;
    ~Child() {
        if (pid > 0) {
            ::kill(pid, SIGKILL);
            reap();
        }
    }
    /// waitpid, retried on EINTR; returns the status (or 0 if it cannot be had).
    int reap() {
        int status = 0;
        while (pid > 0) {
            const pid_t r = ::waitpid(pid, &status, 0);
            if (r == pid || (r < 0 && errno != EINTR)) break;
        }
        pid = -1;
        return status;
    }
};

/// Writes all of [p, p + n) to fd; false on an error (the parent went away).
bool write_all(int fd, const char* p, std::size_t n) {
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n < (std::size_t(1) << 30) ? n : (std::size_t(1) << 30));
        if (w < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        p += w;
        n -= std::size_t(w);
    }
    return true;
}

}  // namespace
}  // namespace normalflow

// Set only when a sanitizer runtime is linked (weak: null otherwise).
extern "C" void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

namespace normalflow {
namespace {

/// In the child: run work, send tag + bytes, leave without running any exit handler.
[[noreturn]] void child_main(int fd, const std::function<std::string()>& work) {
    // A crash must kill the child with its signal (the parent reports which), not run handlers the
    // parent installed (libFuzzer's, a sanitizer's, the app's), which would treat it as their own.
    for (int sig : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGTRAP}) ::signal(sig, SIG_DFL);
    ::signal(SIGPIPE, SIG_IGN);
    // A sanitizer report in the child ends it with a non-zero status; the parent's death callback
    // (libFuzzer writes a crash artifact there) must not run in the child.
    if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);
    char tag = kResult;
    std::string body;
    try {
        body = work();
    } catch (const InvalidInput& e) {
        tag = kInvalidInput, body = e.what();
    } catch (const IoError& e) {
        tag = kIoError, body = e.what();
    } catch (const NumericalError& e) {
        tag = kNumericalError, body = e.what();
    } catch (const Cancelled& e) {
        tag = kCancelled, body = e.what();
    } catch (const OutOfMemory& e) {
        tag = kOutOfMemory, body = e.what();
    } catch (const std::bad_alloc&) {
        tag = kOutOfMemory, body.clear();
    } catch (const std::exception& e) {
        tag = kOther, body = e.what();
    } catch (...) {
        tag = kOther, body = "unknown exception";
    }
    const bool ok = write_all(fd, &tag, 1) && write_all(fd, body.data(), body.size());
    ::_exit(ok ? 0 : 3);
}

std::string signal_text(int sig) {
    std::string s = "signal " + std::to_string(sig);
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 32))
    if (const char* abbrev = ::sigabbrev_np(sig)) s += std::string(", SIG") + abbrev;
#endif
    return s;
}

[[noreturn]] void rethrow(char tag, std::string msg, std::string_view what) {
    switch (tag) {
        case kInvalidInput: throw InvalidInput(msg);
        case kIoError: throw IoError(msg);
        case kNumericalError: throw NumericalError(msg);
        case kCancelled: throw Cancelled(msg);
        case kOutOfMemory:
            throw OutOfMemory(msg.empty() ? std::string(what) + ": out of memory in the isolated process" : msg);
        default: throw IoError(std::string(what) + ": unexpected error in the isolated process (" + msg + ")");
    }
}

}  // namespace

bool isolation_disabled() {
    const char* v = std::getenv("NORMALFLOW_NO_ISOLATION");
    return v && *v && std::strcmp(v, "0") != 0;
}

void ByteReader::fail() const { throw IoError(std::string(what_) + ": the isolated process sent a truncated result"); }

void put_mesh(ByteWriter& w, const Mesh& m) {
    w.put_array(m.positions);
    w.put_array(m.triangles);
    w.put_array(m.normals);
    w.put_array(m.colors);
    w.put_array(m.texcoords);
}

Mesh get_mesh(ByteReader& r) {
    Mesh m;
    m.positions = r.get_array<Vec3f>();
    m.triangles = r.get_array<Tri>();
    m.normals = r.get_array<Vec3f>();
    m.colors = r.get_array<Rgba8>();
    m.texcoords = r.get_array<TexCoord>();
    return m;
}

std::string run_isolated(std::string_view what, const std::function<std::string()>& work, double timeout_seconds) {
    if (isolation_disabled()) return work();
    if (!(timeout_seconds >= 0) || !std::isfinite(timeout_seconds))
        throw InvalidInput(std::string(what) + ": isolation timeout must be finite and >= 0");

    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        throw IoError(std::string(what) + ": cannot create a pipe for the isolated process (" + std::strerror(errno) +
                      ")");
    Fd rd(fds[0]), wr(fds[1]);

    Child child;
    child.pid = ::fork();
    if (child.pid < 0) {
        const int err = errno;
        child.pid = -1;
        if (err == ENOMEM) throw OutOfMemory(std::string(what) + ": cannot fork the isolated process (out of memory)");
        throw IoError(std::string(what) + ": cannot fork the isolated process (" + std::strerror(err) + ")");
    }
    if (child.pid == 0) {
        ::close(fds[0]);
        child_main(fds[1], work);
    }
    wr.reset();  // the parent keeps only the read end: EOF arrives when the child exits

    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(timeout_seconds > 0 ? timeout_seconds : 0));
    std::string bytes;
    std::size_t used = 0;
    for (;;) {
        if (timeout_seconds > 0) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
            if (left <= 0) {
                ::kill(child.pid, SIGKILL);
                child.reap();
                throw IoError(std::string(what) + ": the isolated process did not finish within " +
                              std::to_string(timeout_seconds) + " s and was killed");
            }
            pollfd p{rd.fd, POLLIN, 0};
            const int r = ::poll(&p, 1, int(left < 1000000 ? left : 1000000));
            if (r < 0 && errno != EINTR)
                throw IoError(std::string(what) + ": poll failed (" + std::strerror(errno) + ")");
            if (r <= 0) continue;
        }
        if (bytes.size() - used < (std::size_t(1) << 16))
            bytes.resize(std::max<std::size_t>(bytes.size() * 2, std::size_t(1) << 20));
        const ssize_t n = ::read(rd.fd, bytes.data() + used, bytes.size() - used);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw IoError(std::string(what) + ": cannot read from the isolated process (" + std::strerror(errno) + ")");
        }
        if (n == 0) break;
        used += std::size_t(n);
    }
    bytes.resize(used);
    rd.reset();
    const int status = child.reap();

    if (WIFSIGNALED(status))
        throw IoError(std::string(what) + ": the third-party code crashed (" + signal_text(WTERMSIG(status)) +
                      ") in an isolated process; the input is probably corrupt");
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.empty())
        throw IoError(std::string(what) + ": the isolated process exited with status " +
                      std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                      " without a result (a sanitizer report or an exit() in third-party code?); the input is "
                      "probably corrupt");
    const char tag = bytes[0];
    if (tag != kResult) rethrow(tag, bytes.substr(1), what);
    bytes.erase(0, 1);
    return bytes;
}

}  // namespace normalflow
