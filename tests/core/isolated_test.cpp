#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/detail/isolated.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

// No child is left behind: every run_isolated reaps its process.
void expect_no_children() {
  int status = 0;
  EXPECT_EQ(::waitpid(-1, &status, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

// Work for the processor, `seconds` of it.
void spin(double seconds) {
  const std::clock_t start = std::clock();
  volatile std::uint64_t x = 0;
  while (static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC < seconds) x = x + 1;
}

// A parent that expects one int from its child.
Status read_an_int(ChildInput& in) {
  int x = 0;
  return in.read_value(&x) ? Status{} : Error{"short"};
}

TEST(Isolated, ParentReadsWhatTheChildWrites) {
  std::vector<double> got(3);
  const Status s = run_isolated(
      "the work", {},
      [](ChildOutput& out) {
        const double values[3] = {1.5, -2, 1e300};
        out.write(values, sizeof(values));
      },
      [&](ChildInput& in) -> Status {
        if (!in.read(got.data(), 3 * sizeof(double))) return Error{"short"};
        return {};
      });
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(got, (std::vector<double>{1.5, -2, 1e300}));
  expect_no_children();
}

TEST(Isolated, ALargeAnswerPassesThePipeWhole) {
  const std::size_t n = 50'000'000;  // 200 MB, far beyond a pipe's buffer
  std::vector<std::uint32_t> got(n);
  const Status s = run_isolated(
      "the work", {},
      [&](ChildOutput& out) {
        std::vector<std::uint32_t> values(n);
        for (std::size_t i = 0; i < n; ++i) values[i] = static_cast<std::uint32_t>(i * 2654435761u);
        out.write(values.data(), n * 4);
      },
      [&](ChildInput& in) -> Status {
        return in.read(got.data(), n * 4) ? Status{} : Error{"short"};
      });
  ASSERT_TRUE(s.ok()) << s.error().message;
  for (std::size_t i = 0; i < n; i += 9973)
    ASSERT_EQ(got[i], static_cast<std::uint32_t>(i * 2654435761u));
  EXPECT_EQ(got[n - 1], static_cast<std::uint32_t>((n - 1) * 2654435761u));
}

TEST(Isolated, AChildThatCrashesIsAnErrorNamingTheSignal) {
  const Status s = run_isolated(
      "the decoder", {}, [](ChildOutput&) { std::abort(); }, read_an_int);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the decoder crashed on this input (signal 6: Aborted)");
  expect_no_children();
}

TEST(Isolated, AChildThatCrashesAfterItsAnswerIsStillAnError) {
  const Status s = run_isolated(
      "the decoder", {},
      [](ChildOutput& out) {
        out.write_value(7);
        std::abort();
      },
      [](ChildInput& in) -> Status {
        int x = 0;
        return in.read_value(&x) && x == 7 ? Status{} : Error{"short"};
      });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the decoder crashed on this input (signal 6: Aborted)");
}

TEST(Isolated, AChildThatSpinsIsStoppedAtItsProcessorTime) {
  IsolationLimits limits;
  limits.cpu_seconds = 1;
  const Status s = run_isolated(
      "the decoder", limits, [](ChildOutput&) { spin(1e9); }, read_an_int);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message,
            "the decoder used more than 1 s of processor time on this input and was stopped");
  expect_no_children();
}

// Work whose size the child's first answer tells (an image's texels) gets more time then, without
// privileges (the tests also run as a user who is not root).
TEST(Isolated, TheParentMayGrantMoreProcessorTimeOnTheWay) {
  IsolationLimits limits;
  limits.cpu_seconds = 1;
  const auto child = [&](ChildOutput& out) {
    out.write_value(1);
    spin(2.5);
    out.write_value(2);
  };
  const auto parent = [](bool grant) {
    return [grant](ChildInput& in) -> Status {
      int first = 0, second = 0;
      if (!in.read_value(&first)) return Error{"no first"};
      if (grant) in.allow_more(3);
      if (!in.read_value(&second) || second != 2) return Error{"no second"};
      return {};
    };
  };
  const Status granted = run_isolated("the decoder", limits, child, parent(true));
  EXPECT_TRUE(granted.ok()) << granted.error().message;
  const Status refused = run_isolated("the decoder", limits, child, parent(false));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message,
            "the decoder used more than 1 s of processor time on this input and was stopped");
  expect_no_children();
}

TEST(Isolated, AChildThatWaitsIsStoppedAtTheDeadline) {
  IsolationLimits limits;
  limits.wall_seconds = 0.5;
  const auto start = std::chrono::steady_clock::now();
  const Status s = run_isolated(
      "the decoder", limits,
      [](ChildOutput&) {
        for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
      },
      read_an_int);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the decoder took longer than 0.5 s on this input and was stopped");
  EXPECT_GE(seconds, 0.5);
  EXPECT_LT(seconds, 30);  // not waiting for the child: it was killed
  expect_no_children();
}

TEST(Isolated, AChildThatExceedsItsMemoryIsAnError) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "no address-space limit under AddressSanitizer";
#endif
  IsolationLimits limits;
  limits.memory = 64 << 20;
  const Status s = run_isolated(
      "the decoder", limits,
      [](ChildOutput& out) {
        std::vector<char> huge(std::size_t{1} << 30, 1);
        out.write_value(huge[12345]);
      },
      [](ChildInput& in) -> Status {
        char x = 0;
        return in.read_value(&x) ? Status{} : Error{"short"};
      });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message,
            "the decoder ran out of memory (its limit is 64.0 MiB; raise it with "
            "set_memory_budget())");
}

TEST(Isolated, TheParentsOwnRefusalIsTheAnswerAndTheChildIsEnded) {
  const Status s = run_isolated(
      "the decoder", {},
      [](ChildOutput& out) {
        for (int i = 0;; ++i) out.write_value(i);  // would write forever
      },
      [](ChildInput& in) -> Status {
        int x = 0;
        if (!in.read_value(&x)) return Error{"short"};
        return Error{"the count is absurd"};
      });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the count is absurd");
  expect_no_children();
}

TEST(Isolated, AChildThatExitsEarlyIsAnError) {
  const Status s = run_isolated(
      "the decoder", {}, [](ChildOutput&) { _exit(3); }, read_an_int);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the decoder failed (exit status 3)");
}

TEST(Isolated, AnAnswerThatBreaksOffIsTheParentsError) {
  const Status s = run_isolated(
      "the decoder", {}, [](ChildOutput& out) { out.write_value(std::uint8_t{1}); },
      [](ChildInput& in) -> Status {
        std::uint64_t x = 0;
        return in.read_value(&x) ? Status{} : Error{"broke off"};
      });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "broke off");
}

TEST(Isolated, AChildKilledFromOutsideIsReportedWithItsSignal) {
  // The out-of-memory killer or a user's kill -9: not our kill, so its signal is the message.
  const Status s = run_isolated(
      "the decoder", {}, [](ChildOutput&) { ::raise(SIGKILL); }, read_an_int);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the decoder was killed (signal 9: Killed)");
  const Status term = run_isolated(
      "the decoder", {}, [](ChildOutput&) { ::raise(SIGTERM); }, read_an_int);
  ASSERT_FALSE(term.ok());
  EXPECT_EQ(term.error().message, "the decoder was killed (signal 15: Terminated)");
  expect_no_children();
}

// A child that forks a grandchild (which sleeps, holding the channel) and sends its pid; `after`
// is what the child does then.
enum class After { exit, wait };
std::function<void(ChildOutput&)> leave_a_grandchild(After after) {
  return [after](ChildOutput& out) {
    const pid_t grandchild = ::fork();
    if (grandchild == 0) {
      const int null = ::open("/dev/null", O_RDWR);
      ::dup2(null, 1);  // not the test's output, which ctest waits on
      ::dup2(null, 2);
      ::alarm(300);  // a backstop where it is not killed (the defect this tests)
      for (;;) ::pause();
    }
    out.write_value(static_cast<std::int32_t>(grandchild));
    if (after == After::wait)
      for (;;) ::pause();
  };
}

TEST(Isolated, AChildThatExitsLeavingAGrandchildOnTheChannelIsNotWaitedForAndTheGrandchildDies) {
  // Before, the parent read the channel until the grandchild's end closed it: the deadline (here
  // 120 s, far beyond what the child needs on a loaded machine), and the grandchild lived on.
  IsolationLimits limits;
  limits.wall_seconds = 120;
  std::int32_t grandchild = 0;
  const Status s = run_isolated("the decoder", limits, leave_a_grandchild(After::exit),
                                [&](ChildInput& in) -> Status {
                                  return in.read_value(&grandchild) ? Status{} : Error{"short"};
                                });
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_GT(grandchild, 0);
  EXPECT_TRUE(test::process_dies(grandchild)) << "grandchild " << grandchild << " still runs";
  expect_no_children();
}

TEST(Isolated, AChildThatIsStoppedTakesItsGrandchildrenWithIt) {
  // Stopped because the parent refuses its answer (as at the deadline: the same end, without
  // depending on how fast a loaded machine forks).
  IsolationLimits limits;
  limits.wall_seconds = 120;
  std::int32_t grandchild = 0;
  const Status s = run_isolated("the decoder", limits, leave_a_grandchild(After::wait),
                                [&](ChildInput& in) -> Status {
                                  if (!in.read_value(&grandchild)) return Error{"short"};
                                  return Error{"the answer is refused"};
                                });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "the answer is refused");
  ASSERT_GT(grandchild, 0);
  EXPECT_TRUE(test::process_dies(grandchild)) << "grandchild " << grandchild << " still runs";
  expect_no_children();
}

}  // namespace
}  // namespace lightvol
