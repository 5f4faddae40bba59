#pragma once
/// \file isolate.h
/// Crash isolation for third-party code (issue 7): run a function in a forked child process and get
/// its result bytes back through a pipe, so that a crash inside a third-party decoder (Draco, OpenVDB,
/// TetGen) on a corrupt file becomes a one-line IoError instead of taking the whole process down.
/// Plus a tiny length-prefixed binary layout (ByteWriter / ByteReader) to ship results across.

#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/mesh.h"

namespace normalflow {

/// Runs work() in a forked child process and returns the bytes it returned.
///
/// Method: fork(); the child runs work(), writes a one-byte tag and the result (or, if work() threw,
/// the exception's kind and message) into a pipe and leaves with _exit(0) (no atexit handlers, no
/// static destructors, no leak check in the child). The parent reads everything (EINTR, partial reads
/// and payloads of hundreds of MB are handled), then reaps the child with waitpid. Nothing is leaked:
/// both pipe ends are close-on-exec and closed on every path, the child is always reaped (killed
/// first if the parent itself fails while reading). SIGPIPE is ignored in the child.
///
/// \param what  who and which input, used as the prefix of every message ("read_drc: scan.drc")
/// \param work  the code to isolate; it must be single-threaded (after fork() only the calling thread
///              exists in the child: no TBB, no thread pools). Its result is returned byte for byte.
/// \param timeout_seconds  wall-clock limit for the child, seconds, >= 0; 0 = no limit
/// \return the bytes work() returned in the child
/// \throw the SAME type as work() threw, with the same message, for InvalidInput, IoError,
///        NumericalError, Cancelled and OutOfMemory (std::bad_alloc becomes OutOfMemory; any other
///        exception becomes IoError naming `what`);
///        IoError("<what>: the third-party code crashed (signal 11, SIGSEGV) ...") when the child dies
///        from a signal or exits without a result; IoError when the timeout expires (the child is
///        killed with SIGKILL); IoError (or OutOfMemory) when fork() or pipe() fail.
///
/// Setting the environment variable NORMALFLOW_NO_ISOLATION=1 runs work() in this process instead
/// (for debuggers and profilers); exceptions then propagate unchanged.
/// Cost: one fork() (copy-on-write; about 0.1-1 ms plus page-table copying for a large parent) and
/// one copy of the result through the pipe (about 1-3 GB/s). Thread-safe: concurrent calls from
/// several threads each get their own child and pipe.
std::string run_isolated(std::string_view what, const std::function<std::string()>& work, double timeout_seconds = 0);

/// True when NORMALFLOW_NO_ISOLATION is set to a non-empty value other than "0".
bool isolation_disabled();

/// Appends trivially copyable values and length-prefixed arrays/strings in host byte order (the
/// bytes never leave the machine: they go from a child process to its parent).
class ByteWriter {
public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        const std::size_t n = out_.size();
        out_.resize(n + sizeof(T));
        std::memcpy(out_.data() + n, &v, sizeof(T));
    }
    /// A std::uint64_t element count followed by the raw elements.
    template <class T>
    void put_array(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(std::uint64_t(v.size()));
        if (!v.empty()) out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void put_string(std::string_view s) {
        put(std::uint64_t(s.size()));
        out_.append(s.data(), s.size());
    }
    std::string take() { return std::move(out_); }

private:
    std::string out_;
};

/// Reads what ByteWriter wrote, in the same order. Running past the end throws IoError naming `what`.
class ByteReader {
public:
    ByteReader(std::string_view bytes, std::string_view what) : p_(bytes), what_(what) {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T v;
        std::memcpy(&v, take(sizeof(T)), sizeof(T));
        return v;
    }
    template <class T>
    std::vector<T> get_array() {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto n = get<std::uint64_t>();
        if (n > p_.size() / sizeof(T)) fail();
        std::vector<T> v(static_cast<std::size_t>(n));
        if (n)
            std::memcpy(v.data(), take(static_cast<std::size_t>(n) * sizeof(T)),
                        static_cast<std::size_t>(n) * sizeof(T));
        return v;
    }
    std::string get_string() {
        const auto n = get<std::uint64_t>();
        if (n > p_.size()) fail();
        return std::string(take(static_cast<std::size_t>(n)), static_cast<std::size_t>(n));
    }
    bool at_end() const { return p_.empty(); }

private:
    const char* take(std::size_t n) {
        if (n > p_.size()) fail();
        const char* d = p_.data();
        p_.remove_prefix(n);
        return d;
    }
    [[noreturn]] void fail() const;
    std::string_view p_;
    std::string_view what_;
};

/// Mesh in the ByteWriter layout (positions array, triangles array).
void put_mesh(ByteWriter& w, const Mesh& m);
/// The Mesh put_mesh wrote; throws IoError naming `what` if the bytes are short.
Mesh get_mesh(ByteReader& r);

}  // namespace normalflow
