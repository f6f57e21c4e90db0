// Running untrusted third-party decoding in a child process.
//
// Some decoders lightvol relies on (Draco's) are not hardened against hostile input: no public
// fuzzing covers them, and fuzzing here found crashes, hangs and huge allocations in them. Their
// input is checked as far as its structure can be seen from outside; what remains is contained:
// the work runs in a forked child with an address-space limit (the memory budget), a limit on its
// processor time and a wall-clock deadline, and sends its answer back through a pipe. A crash, a
// hang or an exhausted limit in the child is then an Error for the parent, never a signal, a hang
// or an allocation in it; nothing the child sends is trusted beyond the byte counts the parent
// asked for.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>

namespace lightvol {

// The child's end of the channel (a socket pair). Writes go straight to the parent; a parent that
// stopped reading ends the child. Reads are what the parent sends (requests, its decisions).
class ChildOutput {
 public:
  explicit ChildOutput(int fd) : fd_(fd) {}
  void write(const void* data, std::size_t bytes);
  // Exactly `bytes` from the parent; false when the parent closed its end first.
  bool read(void* data, std::size_t bytes);
  template <class T>
  bool read_value(T* value) {
    return read(value, sizeof(*value));
  }
  // A string as ChildInput::write_string sends it (at most kMaxString bytes).
  bool read_string(std::string* text);
  // One byte as ChildInput::write_with_fd sends it, and the descriptor that came with it (-1:
  // none; it is then the caller's to close). False when the parent closed its end first.
  bool read_with_fd(std::uint8_t* byte, int* fd);
  template <class T>
  void write_value(const T& value) {
    write(&value, sizeof(value));
  }
  // Its length, then its bytes (at most kMaxString of them).
  void write_string(const std::string& text);
  static constexpr std::size_t kMaxString = 4096;
  // The numbers of position floats and of indices, then both arrays.
  void write_mesh(const Mesh& mesh);
  // A verdict before what follows it: the work went on (an answer follows), or was refused.
  void accept() { write_value(std::uint8_t{1}); }
  void refuse(const Error& error);

 private:
  int fd_;
};

// The parent's end: reads exactly the bytes asked for before the deadline, or fails. The child
// itself is watched too (through `pidfd`, a descriptor that becomes readable when it ends, or,
// where the kernel has none (-1), by asking every 50 ms): once it has ended, what it sent is read
// and then nothing more is waited for, even while a process it left behind holds its end of the
// channel.
class ChildInput {
 public:
  ChildInput(int fd, int pid, int pidfd, double cpu_seconds, double deadline)
      : fd_(fd), pid_(pid), pidfd_(pidfd), cpu_(cpu_seconds), deadline_(deadline) {}
  // False (and `timed_out()` true if so) when the child ended, broke off or ran out of time first.
  bool read(void* data, std::size_t bytes);
  template <class T>
  bool read_value(T* value) {
    return read(value, sizeof(*value));
  }
  // A string as ChildOutput::write_string sends it; false if it breaks off or is too long.
  bool read_string(std::string* text);
  // Sends bytes to the child (a request, a decision) before the deadline; false if the child
  // ended or stopped reading first.
  bool write(const void* data, std::size_t bytes);
  template <class T>
  bool write_value(const T& value) {
    return write(&value, sizeof(value));
  }
  bool write_string(const std::string& text);
  // Sends one byte with a copy of descriptor `fd` (SCM_RIGHTS; -1: the byte alone), before the
  // deadline; false if the child ended or stopped reading first, or the kernel refused the
  // descriptor.
  bool write_with_fd(std::uint8_t byte, int fd);
  // A mesh as ChildOutput::write_mesh sends it, checked: whole triangles, every index naming a
  // vertex, fewer than 2^32 vertices, the arrays within the memory budget (an Error naming
  // `source` if not). False if the answer breaks off or does not hold together.
  bool read_mesh(Mesh* mesh, const std::string& source, Status* refused);
  // A verdict as ChildOutput::accept or refuse sends it (`*refusal` the refusal's Error).
  enum class Verdict { accepted, refused, broken };
  Verdict read_verdict(Error* refusal);
  // The verdict in a conversation whose result is `*result`: true when the child went on; else
  // false with `*answer` saying how the conversation ends (a refusal becomes `*result` and the
  // conversation ends well; a broken answer ends it with `broken`).
  template <class T>
  bool read_go_on(Result<T>* result, const Error& broken, Status* answer) {
    Error refusal;
    switch (read_verdict(&refusal)) {
      case Verdict::accepted:
        return true;
      case Verdict::refused:
        *result = std::move(refusal);
        *answer = {};
        return false;
      case Verdict::broken:
        *answer = broken;
        return false;
    }
    return false;
  }
  bool timed_out() const { return timed_out_; }
  // The channel was closed, or broke, under a read or a send (the child ended or closed its end).
  bool closed() const { return closed_; }
  // Grants the child `cpu_seconds` more processor time, and four times that more wall-clock time:
  // for work whose size only the child's first answer tells (an image's texel count).
  void allow_more(double cpu_seconds);
  double cpu_seconds() const { return cpu_; }
  double wall_seconds_added() const { return wall_added_; }

 private:
  // Reads (or sends) all `bytes` before the deadline, polling the channel; false as read() says.
  bool transfer(char* data, std::size_t bytes, bool sending, int attach = -1);

  int fd_;
  int pid_;
  int pidfd_;           // readable once the child ended; -1: none (the kernel is asked instead)
  bool ended_ = false;  // the child ended (seen through pidfd_ or waitid)
  double cpu_;          // processor seconds granted (the child's RLIMIT_CPU)
  double deadline_;     // seconds on the monotonic clock
  double wall_added_ = 0;
  bool timed_out_ = false;
  bool closed_ = false;
};

struct IsolationLimits {
  // Processor time the child may use (the kernel's RLIMIT_CPU, rounded down to whole seconds, at
  // least 1): a limit on work that a loaded machine does not tighten.
  double cpu_seconds = 10;
  // Wall-clock time from start to the last byte, a backstop for a child that waits instead of
  // working.
  double wall_seconds = 60;
  std::uint64_t memory = 0;  // bytes the child may allocate beyond what it inherits; 0: the budget
  // What the message says to do when `memory` ran out.
  std::string memory_advice = "raise it with set_memory_budget()";
};

// Runs `child` in a forked process and `parent` on what it writes. `child` must not use threads
// (only the forking thread exists in the child). The result is `parent`'s, unless the child was
// killed by a signal, ran out of time, or exited otherwise than after `child` returned: then it is
// an Error "<what> crashed on this input (signal N: name)", "<what> was killed (signal N: name)"
// (SIGKILL, SIGTERM, SIGINT or SIGHUP from outside: the kernel's out-of-memory killer, a user),
// "<what> used more than S s of processor time ...", "<what> took longer than S s ...", "<what> ran
// out of memory ..." or "<what> failed ...". When `parent` fails because the child's answer broke
// off, the child's fate is the message. Where fork is not possible the Error says so.
//
// The child (like an IsolatedServer's program) leads a process group of its own. When it has ended
// or is stopped, the whole group is killed with SIGKILL before the child is reaped: a process it
// forked cannot outlive it, and one that holds the channel open does not keep the parent waiting
// (a process that leaves the group, by setsid or setpgid, is beyond this).
Status run_isolated(const std::string& what, const IsolationLimits& limits,
                    const std::function<void(ChildOutput&)>& child,
                    const std::function<Status(ChildInput&)>& parent);

// The program side of a server (IsolatedServer): `argv[0]` (a path) started with posix_spawn, a
// fresh process that inherits nothing but its environment, its standard error (also as its
// standard output, so that nothing it prints mixes with ours) and the channel as file descriptor
// kProgramChannel. It may use threads. It writes kProgramReady once loaded and after each request.
constexpr int kProgramChannel = 3;
constexpr std::uint8_t kProgramReady = 0x6c;

// A program that answers many requests, one at a time: started once, kept while it answers each
// request whole. Before each request the parent sets the
// program's limits afresh (its processor time so far plus `cpu_seconds`, its address space now
// plus `memory`); after it, the program writes kProgramReady again. A request that fails in the
// program (a crash, a limit, a broken answer, no kProgramReady) ends it, reaps it, and is the
// Error run_isolated would report; the server is then no longer alive. Not thread-safe: one
// request at a time (callers keep a pool).
class IsolatedServer {
 public:
  // Starts `argv[0]` and waits (up to `wall_seconds`) until it is loaded; an Error "<what> could
  // not be started (<argv[0]>: <reason>)" if it cannot be, or ends before it is ready.
  static Result<std::unique_ptr<IsolatedServer>> start(const std::string& what,
                                                       const std::vector<std::string>& argv,
                                                       double wall_seconds);
  ~IsolatedServer();  // closes the channel (the program then ends) and reaps it
  IsolatedServer(const IsolatedServer&) = delete;
  IsolatedServer& operator=(const IsolatedServer&) = delete;
  Status request(const std::string& what, const IsolationLimits& limits,
                 const std::function<Status(ChildInput&)>& parent);
  bool alive() const { return pid_ > 0; }
  int pid() const { return pid_; }

 private:
  IsolatedServer(int pid, int fd, int pidfd) : pid_(pid), fd_(fd), pidfd_(pidfd) {}
  int pid_;
  int fd_;
  int pidfd_;  // see ChildInput
};

// Exit statuses of a child (or program) that could not finish its work, beside 0: out of memory
// (std::bad_alloc), an exception, the parent gone.
constexpr int kChildOutOfMemory = 97, kChildThrew = 98, kChildBrokenPipe = 99;

}  // namespace lightvol
