// Images are read and written by lightvol-image, a server process the library starts
// (core/detail/image_helper.h): concurrent readers, and a decoder that crashes or hangs.
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/detail/image_file.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

DepthImage ramp(int w, int h, float offset) {
  return test::make_depth(
      w, h, [offset, w](int c, int r) { return offset + 0.001f * static_cast<float>(c + w * r); });
}

TEST(ImageHelper, ReadsFromFourThreadsAtOnceGiveEachItsPixels) {
  test::TempDir dir;
  std::vector<DepthImage> images;
  std::vector<std::string> paths;
  const char* names[] = {"a.exr", "b.tif", "c.exr", "d.png"};
  for (int i = 0; i < 4; ++i) {
    images.push_back(ramp(64 + i, 48, static_cast<float>(i)));
    if (i == 3)  // 16-bit PNG: normalized window depth, exact at multiples of 1/65535
      images.back() =
          test::make_depth(67, 48, [](int c, int r) { return static_cast<float>(c + r) / 65535; });
    paths.push_back(dir.file(names[i]));
    ASSERT_TRUE(write_depth_image(paths.back(), images.back()).ok());
  }
  std::vector<std::string> failures(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int round = 0; round < 3; ++round) {
        const int i = (t + round) % 4;
        const Result<DepthImage> read = read_depth_image(paths[i]);
        if (!read) {
          failures[t] = read.error().message;
          return;
        }
        if (read->width != images[i].width || read->height != images[i].height) {
          failures[t] = paths[i] + ": wrong size";
          return;
        }
        for (std::size_t k = 0; k < read->values.size(); ++k)
          if (std::abs(read->values[k] - images[i].values[k]) > 0.5f / 65535) {
            failures[t] = paths[i] + ": wrong value at " + std::to_string(k);
            return;
          }
      }
    });
  for (std::thread& t : threads) t.join();
  for (const std::string& f : failures) EXPECT_EQ(f, "");
}

// LIGHTVOL_IMAGE_HELPER names the fake helper (tests/depth/fake_image_helper.cpp) while alive.
class FakeHelper {
 public:
  FakeHelper() {
    detail::close_idle_image_servers();
    ::setenv("LIGHTVOL_IMAGE_HELPER", LIGHTVOL_FAKE_IMAGE_HELPER, 1);
  }
  ~FakeHelper() {
    ::unsetenv("LIGHTVOL_IMAGE_HELPER");
    detail::close_idle_image_servers();
  }
};

TEST(ImageHelper, ACrashingDecoderIsAnErrorNamingTheFileAndTheNextReadWorks) {
  test::TempDir dir;
  const DepthImage image = ramp(8, 6, 1);
  const std::string crash = dir.file("crash.exr"), fine = dir.file("fine.exr");
  ASSERT_TRUE(write_depth_image(crash, image).ok());
  ASSERT_TRUE(write_depth_image(fine, image).ok());
  const FakeHelper fake;
  const Result<DepthImage> crashed = read_depth_image(crash);
  ASSERT_FALSE(crashed.ok());
  EXPECT_EQ(crashed.error().message,
            crash + ": OpenImageIO's reader crashed on this input (signal 11: Segmentation fault)");
  const Result<DepthImage> read = read_depth_image(fine);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->values, image.values);
  // Decoded into the memfd this process offered, and used where it lies.
  EXPECT_TRUE(read->values.mapped());
}

TEST(ImageHelper, WithoutSharedMemoryTheFloatsComeThroughTheChannel) {
  test::TempDir dir;
  const DepthImage image = ramp(64, 48, 1);
  const std::string path = dir.file("ramp.exr");
  ASSERT_TRUE(write_depth_image(path, image).ok());
  detail::offer_shared_memory(false);
  const Result<DepthImage> through_channel = read_depth_image(path);
  detail::offer_shared_memory(true);
  ASSERT_TRUE(through_channel.ok()) << through_channel.error().message;
  EXPECT_FALSE(through_channel->values.mapped());
  EXPECT_EQ(through_channel->values, image.values);
  const Result<DepthImage> shared = read_depth_image(path);
  ASSERT_TRUE(shared.ok()) << shared.error().message;
  EXPECT_TRUE(shared->values.mapped());
  EXPECT_EQ(shared->values, image.values);
}

// A read request for `path`, whose answer the fake helper may withhold: OK when a verdict came
// back.
Status read_request(const std::string& path, double wall_seconds) {
  IsolationLimits limits;
  limits.wall_seconds = wall_seconds;
  return detail::run_image_helper(path + ": the reader", limits, [&](ChildInput& in) {
    std::uint8_t verdict = 0;
    if (!in.write_value(detail::ImageRequest::read) || !in.write_string(path) ||
        !in.write_string("openexr") || !in.write_string("") || !in.write_string("") ||
        !in.read_value(&verdict))
      return Status{Error{"no answer"}};
    return Status{};
  });
}

TEST(ImageHelper, AHangingDecoderIsStoppedAtTheDeadlineAndTheNextRequestWorks) {
  const FakeHelper fake;
  // A read request for a path the fake helper hangs on: nothing comes back.
  const Status hung = read_request("hang.exr", 0.5);
  ASSERT_FALSE(hung.ok());
  EXPECT_EQ(hung.error().message,
            "hang.exr: the reader took longer than 0.5 s on this input and was stopped");
  test::TempDir dir;
  const DepthImage image = ramp(5, 4, 2);
  ASSERT_TRUE(write_depth_image(dir.file("after.pfm"), image).ok());
  const Result<DepthImage> read = read_depth_image(dir.file("after.pfm"));
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->values, image.values);
}

TEST(ImageHelper, AKilledDecoderIsReportedWithItsSignal) {
  // SIGKILL from outside (the out-of-memory killer, kill -9) was reported as an answer that broke
  // off, without the signal.
  const FakeHelper fake;
  const Status killed = read_request("killed.exr", 120);
  ASSERT_FALSE(killed.ok());
  EXPECT_EQ(killed.error().message, "killed.exr: the reader was killed (signal 9: Killed)");
}

// The fake helper, started with $LIGHTVOL_FAKE_GRANDCHILD: it leaves a grandchild that holds the
// channel, whose pid pid() reads.
class FakeHelperWithGrandchild {
 public:
  FakeHelperWithGrandchild() : pid_file_(dir_.file("grandchild.pid")) {
    ::setenv("LIGHTVOL_FAKE_GRANDCHILD", pid_file_.c_str(), 1);
  }
  ~FakeHelperWithGrandchild() { ::unsetenv("LIGHTVOL_FAKE_GRANDCHILD"); }
  int pid() const { return std::atoi(test::slurp(pid_file_).c_str()); }

 private:
  test::TempDir dir_;
  std::string pid_file_;
  FakeHelper fake_;
};

TEST(ImageHelper, ADecoderThatExitsLeavingAGrandchildOnTheChannelIsNotWaitedFor) {
  // The helper exits; its grandchild holds the channel open. Before, the request waited for the
  // channel to close, i.e. until the deadline (60 s in a build; 120 s here, far beyond what the
  // helper takes to exit on a loaded machine), and the grandchild lived on.
  const FakeHelperWithGrandchild fake;
  const Status exited = read_request("exit.exr", 120);
  ASSERT_FALSE(exited.ok());
  EXPECT_EQ(exited.error().message, "exit.exr: the reader failed (exit status 3)");
  ASSERT_GT(fake.pid(), 0);
  EXPECT_TRUE(test::process_dies(fake.pid())) << "grandchild " << fake.pid() << " still runs";
}

TEST(ImageHelper, ADecoderStoppedAtTheDeadlineTakesItsGrandchildrenWithIt) {
  // The grandchild exists (its pid written) before the helper is ready, so the short deadline
  // does not race with it.
  const FakeHelperWithGrandchild fake;
  const Status hung = read_request("hang.exr", 0.5);
  ASSERT_FALSE(hung.ok());
  EXPECT_EQ(hung.error().message,
            "hang.exr: the reader took longer than 0.5 s on this input and was stopped");
  ASSERT_GT(fake.pid(), 0);
  EXPECT_TRUE(test::process_dies(fake.pid())) << "grandchild " << fake.pid() << " still runs";
}

TEST(ImageHelper, AnIdleServerClosedAtTheEndTakesItsGrandchildrenWithIt) {
  int grandchild = 0;
  {
    const FakeHelperWithGrandchild fake;
    test::TempDir dir;
    const DepthImage image = ramp(5, 4, 2);
    ASSERT_TRUE(write_depth_image(dir.file("fine.exr"), image).ok());  // through the helper
    grandchild = fake.pid();
  }  // the idle server is closed here
  ASSERT_GT(grandchild, 0);
  EXPECT_TRUE(test::process_dies(grandchild)) << "grandchild " << grandchild << " still runs";
}

TEST(ImageHelper, AMissingProgramIsAnErrorSayingWhere) {
  detail::close_idle_image_servers();
  ::setenv("LIGHTVOL_IMAGE_HELPER", "/nonexistent/lightvol-image", 1);
  const Result<DepthImage> read =
      read_depth_image(std::string(LIGHTVOL_SOURCE_DIR) + "/data/synthetic_256.exr");
  ::unsetenv("LIGHTVOL_IMAGE_HELPER");
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find(
                "LIGHTVOL_IMAGE_HELPER names /nonexistent/lightvol-image, which is not an "
                "executable file"),
            std::string::npos)
      << read.error().message;
}

}  // namespace
}  // namespace lightvol
