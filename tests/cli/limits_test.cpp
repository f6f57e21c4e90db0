// Hostile input: forged headers are refused with their message before any large allocation;
// every CLI failure is exit 2 with one line naming the file, never a signal, never an output.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/check/check.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/stages.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/light.h>
#include <lightvol/render/image_io.h>

#include "support/test_support.h"

// The largest single operator new request in this process, libraries included (this replacement
// interposes theirs): a header that makes OpenEXR reserve 1.7 GB without touching it leaves the
// resident peak flat, so peak_memory_bytes() alone would not see it.
namespace {
std::atomic<std::size_t> g_largest_new{0};

void* counted_new(std::size_t n) {
  std::size_t seen = g_largest_new.load(std::memory_order_relaxed);
  while (n > seen && !g_largest_new.compare_exchange_weak(seen, n, std::memory_order_relaxed)) {
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) { return counted_new(n); }
void* operator new[](std::size_t n) { return counted_new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace lightvol {
namespace {

using test::TempDir;

// Runs `f` and returns the largest single allocation it made.
template <class F>
std::size_t largest_allocation(F&& f) {
  g_largest_new = 0;
  f();
  return g_largest_new.load();
}

constexpr std::uint64_t kSmall = std::uint64_t{100} << 20;  // 100 MB of peak growth allowed

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

std::string pfm(int width, int height, std::size_t float_count) {
  std::string bytes = "Pf\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
  bytes.append(float_count * sizeof(float), '\0');
  return bytes;
}

std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

TEST(MemorySize, ParsesUnitsAndRefusesNonsense) {
  EXPECT_EQ(*parse_memory_size("2000000000"), 2000000000u);
  EXPECT_EQ(*parse_memory_size("512M"), std::uint64_t{512} << 20);
  EXPECT_EQ(*parse_memory_size("8g"), std::uint64_t{8} << 30);
  EXPECT_EQ(*parse_memory_size("1.5GiB"), std::uint64_t{3} << 29);
  EXPECT_EQ(*parse_memory_size("64KB"), std::uint64_t{64} << 10);
  EXPECT_EQ(*parse_memory_size("2GB"), std::uint64_t{2} << 30);
  EXPECT_EQ(*parse_memory_size("512B"), 512u);
  // Before: the suffix was upper-cased first, so "1Gb" (gigabits) and "1GIB" passed for 1 GiB;
  // the number went through std::stod.
  for (const char* bad :
       {"",     "lots", "8X",      "-1G", "0",    "1GG", ".",   "8 G", "1Gb", "1gb", "1GIB",
        "1gib", "1Gib", "1GBytes", "1e9", "0x10", "inf", "nan", "+1G", " 1G", "1b",  "1KiBs"}) {
    const Result<std::uint64_t> r = parse_memory_size(bad);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_TRUE(contains(r.error().message, "'" + std::string(bad) + "' is not a memory size"))
        << r.error().message;
  }
}

TEST(MemoryBudget, DefaultIsThreeQuartersOfPhysicalMemory) {
  const std::uint64_t physical = physical_memory_bytes();
  ASSERT_GT(physical, 0u);
  EXPECT_EQ(default_memory_budget(), physical / 4 * 3);
  EXPECT_EQ(memory_budget(), default_memory_budget());
  set_memory_budget(std::uint64_t{1} << 30);
  EXPECT_EQ(memory_budget(), std::uint64_t{1} << 30);
  const Status s = check_memory(std::uint64_t{3} << 30, "x.exr", "a volume");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message,
            "x.exr: a volume needs about 3.0 GiB of memory, more than the budget of 1.0 GiB; raise "
            "it with set_memory_budget() (e.g. to 4G)");
  EXPECT_TRUE(check_memory(std::uint64_t{1} << 30, "x.exr", "a volume").ok());
  set_memory_budget(0);  // back to the default
  EXPECT_EQ(memory_budget(), default_memory_budget());
}

TEST(ForgedHeaders, HugeImageIsRefusedBeforeAllocating) {
  TempDir dir;
  const std::string path = dir.write("huge.pfm", pfm(100000, 100000, 16));
  const std::uint64_t before = peak_memory_bytes();
  const Result<DepthImage> image = read_depth_image(path);
  ASSERT_FALSE(image.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_TRUE(
      contains(image.error().message, path + ": a volume from 100000x100000 texels needs about"))
      << image.error().message;
  EXPECT_TRUE(contains(image.error().message, "set_memory_budget()")) << image.error().message;
}

TEST(ForgedHeaders, HugeReferenceImageIsRefusedBeforeAllocating) {
  // render --compare reads its reference through the same checked opening as depth images.
  TempDir dir;
  const std::string path = dir.write("huge.pfm", pfm(100000, 100000, 16));
  const std::uint64_t before = peak_memory_bytes();
  const Result<Image> image = read_image(path);
  ASSERT_FALSE(image.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_TRUE(contains(image.error().message, path + ": a 100000x100000 image needs about"))
      << image.error().message;
  const Result<Image> device = read_image("/dev/zero");
  ASSERT_FALSE(device.ok());
  EXPECT_EQ(device.error().message,
            "/dev/zero: is not a regular file (a device or a pipe); images are read from files");
}

TEST(ForgedHeaders, TruncatedPfmWithinBudgetIsRefusedBeforeAllocating) {
  TempDir dir;
  // 8000 x 8000 floats (256 MB) promised, 64 bytes present.
  const std::string path = dir.write("short.pfm", pfm(8000, 8000, 16));
  const std::uint64_t before = peak_memory_bytes();
  const Result<DepthImage> image = read_depth_image(path);
  ASSERT_FALSE(image.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_TRUE(contains(image.error().message, path + ": PFM header says 8000x8000"))
      << image.error().message;
  EXPECT_TRUE(contains(image.error().message, "truncated")) << image.error().message;
}

TEST(ForgedHeaders, ExrAttributeClaimingTwoGigabytes) {
  // Found by fuzz_depth_image: OpenEXR allocated the 1.9 GB a string attribute claimed.
  TempDir dir;
  const std::string path = dir.write(
      "bad.exr", test::fuzz_regression_file("depth_image", "regression_exr_attribute_2gb"));
  const std::uint64_t before = peak_memory_bytes();
  Result<DepthImage> image = DepthImage{};
  EXPECT_LT(largest_allocation([&] { image = read_depth_image(path); }), kSmall);
  ASSERT_FALSE(image.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_EQ(image.error().message, path +
                                       ": EXR header: attribute 'Software' claims 1912602678 "
                                       "bytes, but the file has 516 (truncated or corrupt)");
}

TEST(ForgedHeaders, ExrWithARepeatedAttribute) {
  // Found by fuzz_depth_image, twice: on a header that repeats an attribute, OpenEXR's C++ reader
  // (after reading a channel list past its stated size) and its C core (resuming inside the
  // repeated value) both read text as an attribute size and reserved 1.7 GB. Refused first.
  for (const char* name :
       {"regression_exr_opaque_attribute", "regression_exr_repeated_attribute"}) {
    TempDir dir;
    const std::string path = dir.write("bad.exr", test::fuzz_regression_file("depth_image", name));
    Result<DepthImage> image = DepthImage{};
    EXPECT_LT(largest_allocation([&] { image = read_depth_image(path); }), kSmall);
    ASSERT_FALSE(image.ok());
    EXPECT_EQ(image.error().message,
              path + ": EXR header: attribute 'Software' appears twice (corrupt)");
  }
}

TEST(ForgedHeaders, ExrChannelListRunningPastItsSize) {
  // Found by fuzz_depth_image: OpenEXR's core read a channel list past its stated 19 bytes, then
  // text as a 1.9 GB attribute size. Attribute values are checked against their types first.
  TempDir dir;
  const std::string path =
      dir.write("chlist.exr",
                test::fuzz_regression_file("depth_image", "regression_exr_channel_list_overrun"));
  Result<DepthImage> image = DepthImage{};
  EXPECT_LT(largest_allocation([&] { image = read_depth_image(path); }), kSmall);
  ASSERT_FALSE(image.ok());
  EXPECT_EQ(image.error().message, path +
                                       ": EXR header: attribute 'channels' (chlist): the channel "
                                       "list has no end (corrupt)");
}

TEST(ForgedHeaders, ExrWithFarFewerBytesThanChunks) {
  // Found by fuzz_depth_image: a 440-byte EXR whose header says 4x6907652 made OpenEXR walk (and
  // allocate for) 431,729 missing chunks. The chunk offset table alone would need 8 bytes each.
  TempDir dir;
  const std::string path = dir.write(
      "cut.exr", test::fuzz_regression_file("depth_image", "regression_exr_missing_chunks"));
  Result<DepthImage> image = DepthImage{};
  EXPECT_LT(largest_allocation([&] { image = read_depth_image(path); }), kSmall);
  ASSERT_FALSE(image.ok());
  EXPECT_EQ(image.error().message,
            path +
                ": EXR of 4x6907652 has 431729 chunks, needing at least 6907664 bytes, but the "
                "file has 440 (truncated file?)");
}

TEST(ForgedHeaders, ImageLargerThanAnyCompressionOfItsFile) {
  // Found by CI's fixed-seed fuzz run: 445 bytes of EXR claiming 6894084x17 made OpenImageIO
  // allocate 7 GB. No format decodes more than about 1,100 bytes per stored byte.
  TempDir dir;
  const std::string path = dir.write(
      "big.exr", test::fuzz_regression_file("depth_image", "regression_image_beyond_compression"));
  Result<DepthImage> image = DepthImage{};
  EXPECT_LT(largest_allocation([&] { image = read_depth_image(path); }), kSmall);
  ASSERT_FALSE(image.ok());
  EXPECT_EQ(image.error().message,
            path +
                ": is 6894084x17 with 1 channels, 468797712 bytes, in a file of 445: more than "
                "any compression holds (truncated or forged)");
}

TEST(ForgedHeaders, BudgetRefusesAnImageTheMachineCouldHold) {
  TempDir dir;
  const std::string path = dir.write("d.pfm", pfm(256, 256, 256 * 256));
  set_memory_budget(std::uint64_t{1} << 20);
  const Result<DepthImage> refused = read_depth_image(path);
  set_memory_budget(0);
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(
      contains(refused.error().message, "136.4 MiB of memory, more than the budget of 1.0 MiB"))
      << refused.error().message;
  EXPECT_TRUE(read_depth_image(path).ok());
}

TEST(ForgedHeaders, PlyAnnouncingTwoToThe31FacesIn1KB) {
  TempDir dir;
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 2147483648\n"
      "property list uchar int vertex_indices\nend_header\n";
  ply.resize(1024, '\0');
  const std::string path = dir.write("forged.ply", ply);
  const std::uint64_t before = peak_memory_bytes();
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_EQ(mesh.error().message, path +
                                      ": PLY header: 2147483648 face elements cannot fit in 1024 "
                                      "bytes (truncated file?)");
}

TEST(ForgedHeaders, PlyWithAHugeListCount) {
  TempDir dir;
  // One face whose list claims 255 indices (uchar count) or 2^31 − 1 (uint count), in a file
  // holding three: refused, without allocating what the count claims.
  for (const bool wide : {false, true}) {
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list " +
        std::string(wide ? "uint" : "uchar") + " int vertex_indices\nend_header\n";
    const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
    if (wide) {
      const std::uint32_t count = 0x7fffffff;
      ply.append(reinterpret_cast<const char*>(&count), sizeof count);
    } else {
      ply.push_back(static_cast<char>(255));
    }
    const std::int32_t idx[3] = {0, 1, 2};
    ply.append(reinterpret_cast<const char*>(idx), sizeof idx);
    const std::string path = dir.write(wide ? "wide.ply" : "list.ply", ply);
    Result<Mesh> mesh = Mesh{};
    EXPECT_LT(largest_allocation([&] { mesh = read_mesh(path); }), kSmall);
    ASSERT_FALSE(mesh.ok());
    EXPECT_EQ(mesh.error().message.rfind(path + ": ", 0), 0u) << mesh.error().message;
  }
}

TEST(ForgedHeaders, AsciiPlyListLongerThanItsLine) {
  // Found by fuzz_mesh: OpenMesh fills in every vertex an ASCII list count promises (2 GB for
  // this one). Each element is a line, so the count is bounded by what is left of it.
  TempDir dir;
  const std::string path = dir.write(
      "count.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n300000000 0 1 2\n");
  Result<Mesh> mesh = Mesh{};
  EXPECT_LT(largest_allocation([&] { mesh = read_mesh(path); }), kSmall);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().message,
            path + ": PLY body line 4: a list of 300000000 items on a line of 4 values");
}

TEST(ForgedHeaders, PlyWhoseHeaderNeverEnds) {
  // Found by fuzz_mesh: OpenMesh's PLY reader looped forever on "end_header;".
  TempDir dir;
  const std::string path = dir.write(
      "noend.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header;\n0\n1\n2\n");
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().message, path + ": PLY header line 5: unknown keyword 'end_header;'");
  // A header of comments that never ends: only its first 64 KiB are read.
  std::string comments = "ply\nformat ascii 1.0\n";
  while (comments.size() < (1 << 17)) comments += "comment the header goes on\n";
  const std::string endless = dir.write("endless.ply", comments + "end_header\n");
  const Result<Mesh> never = read_mesh(endless);
  ASSERT_FALSE(never.ok());
  EXPECT_EQ(never.error().message, endless + ": PLY header has no 'end_header' line");
  const std::string junk = dir.write(
      "junk.ply", "ply\nformat ascii 1.0\nelement vertex 3\nbogus line\nend_header\n0\n1\n2\n");
  const Result<Mesh> bad = read_mesh(junk);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message, junk + ": PLY header line 4: unknown keyword 'bogus'");
  // Found by fuzz_mesh: OpenMesh's PLY reader also looped forever on an unknown property type.
  for (const char* property : {"property \xff\xff y", "property float", "property list uchar y",
                               "property list uchar bogus vertex_indices"}) {
    const std::string typed = dir.write(
        "typed.ply", std::string("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n") +
                         property + "\nend_header\n0 0\n1 1\n2 2\n");
    const Result<Mesh> r = read_mesh(typed);
    ASSERT_FALSE(r.ok()) << property;
    EXPECT_EQ(
        r.error().message.rfind(typed + ": PLY header line 5: expected 'property TYPE NAME'", 0),
        0u)
        << r.error().message;
  }
}

TEST(ForgedHeaders, OffAnnouncingBillionsOfVertices) {
  TempDir dir;
  const std::string path =
      dir.write("forged.off", "OFF\n3000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const Result<Mesh> mesh = read_mesh(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_TRUE(contains(mesh.error().message, path + ": OFF header: 3000000000 vertices"))
      << mesh.error().message;
}

TEST(ForgedHeaders, OffFaceClaimingHalfABillionVertices) {
  // Found by fuzz_mesh: OpenMesh's OFF reader pushed every vertex a face's count claimed, 12 GB
  // for this 40-byte file. lightvol reads OFF itself and bounds each count by its line.
  TempDir dir;
  const std::string path =
      dir.write("face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n500000000 0 1 2\n");
  Result<Mesh> mesh = Mesh{};
  EXPECT_LT(largest_allocation([&] { mesh = read_mesh(path); }), kSmall);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().message,
            path +
                ": OFF line 6: expected a face: a vertex count of at least 3, then that many "
                "vertices");
}

TEST(ForgedHeaders, JsonNested100000Deep) {
  for (const auto& [open, close] : {std::pair<std::string, std::string>{"[", "]"},
                                    std::pair<std::string, std::string>{"{\"a\":", "}"}}) {
    std::string json;
    for (int i = 0; i < 100000; ++i) json += open;
    json += "1";
    for (int i = 0; i < 100000; ++i) json += close;
    const std::uint64_t before = peak_memory_bytes();
    const Result<Light> light = parse_light(json, "deep.json");
    ASSERT_FALSE(light.ok());
    EXPECT_LT(peak_memory_bytes() - before, kSmall);
    EXPECT_EQ(light.error().message.rfind("deep.json: ", 0), 0u) << light.error().message;
    // Unterminated: the parser stops at the end, still without recursion.
    const Result<Light> cut = parse_light(json.substr(0, 100000), "cut.json");
    ASSERT_FALSE(cut.ok());
    EXPECT_EQ(cut.error().message.rfind("cut.json: ", 0), 0u) << cut.error().message;
  }
}

TEST(ForgedHeaders, CubeMapWhoseFacesDisagree) {
  TempDir dir;
  std::vector<std::string> paths;
  for (int f = 0; f < kOmniFaces; ++f) {
    const int w = f == 3 ? 8 : 4;  // -Y is 8x8, the others 4x4
    std::string bytes = "Pf\n" + std::to_string(w) + " " + std::to_string(w) + "\n-1.0\n";
    const float half = 0.5f;
    for (int i = 0; i < w * w; ++i) bytes.append(reinterpret_cast<const char*>(&half), sizeof half);
    paths.push_back(dir.write("face" + std::to_string(f) + ".pfm", bytes));
  }
  const Result<CubeFaces> cube = read_cube_faces(paths);
  ASSERT_FALSE(cube.ok());
  EXPECT_TRUE(contains(cube.error().message, paths[3])) << cube.error().message;
  EXPECT_TRUE(contains(cube.error().message, "-Y")) << cube.error().message;

  // A face announcing 100000x100000 is refused from its header, counting all six faces.
  paths[3] = dir.write("huge.pfm", pfm(100000, 100000, 4));
  const std::uint64_t before = peak_memory_bytes();
  const Result<CubeFaces> huge = read_cube_faces(paths);
  ASSERT_FALSE(huge.ok());
  EXPECT_LT(peak_memory_bytes() - before, kSmall);
  EXPECT_TRUE(contains(huge.error().message, "100000x100000 texels x 6 needs about"))
      << huge.error().message;
}

TEST(Adversarial, AllFacesShareOneVertex) {
  // A fan of 200,000 triangles around one vertex, every one also sharing its other edges: the
  // checks bucket edges by lower vertex, so the hub must not make them quadratic.
  Mesh fan;
  const int n = 200000;
  fan.positions = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const double a = 2 * 3.14159265358979 * i / n;
    fan.positions.insert(fan.positions.end(),
                         {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 1});
  }
  for (int i = 0; i < n; ++i)
    fan.indices.insert(fan.indices.end(), {0u, static_cast<std::uint32_t>(1 + i),
                                           static_cast<std::uint32_t>(1 + (i + 1) % n)});
  const CheckReport report = check_volume_linear(fan, nullptr);
  EXPECT_EQ(report.triangles, static_cast<std::uint64_t>(n));
  EXPECT_FALSE(report.valid());  // open: the rim is a boundary
}

TEST(Cli, BytesQuotedFromAFileCannotSteerTheTerminal) {
  // An escape sequence, a NUL and a line break quoted from a header come out as \xNN, on one line.
  TempDir dir;
  const std::string path = dir.write(
      "esc.ply", std::string("ply\nformat ascii 1.0\n\x1b[31mRED\0x\rmore\nend_header\n", 48));
  const test::CommandResult r = test::run_lightvol("check " + path);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err,
            "lightvol: " + path + ": PLY header line 3: unknown keyword '\\x1b[31mRED\\x00x'\n");
}

TEST(Cli, ForgedInputsExitTwoWithOneLineAndNoOutput) {
  TempDir dir;
  const std::string light = dir.write("spot.json", test::spot_json());
  const std::string huge = dir.write("huge.pfm", pfm(100000, 100000, 16));
  const std::string out = dir.file("v.ply");
  // An existing output stays as it was.
  const std::string existing = dir.write("old.ply", "keep me");

  struct Case {
    std::string args, names;
  };
  const Case cases[] = {
      {"build " + huge + " --light " + light + " --out " + out, huge},
      {"build " + huge + " --light " + light + " --out " + existing, huge},
      {"stats " + huge + " --light " + light, huge},
      {"build " + dir.write("d.pfm", pfm(256, 256, 256 * 256)) + " --light " + light + " --out " +
           out + " --max-memory 1M",
       dir.file("d.pfm")},
      {"check " + dir.write("forged.ply",
                            "ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\n"
                            "end_header\n"),
       dir.file("forged.ply")},
      {"build " + dir.file("d.pfm") + " --light " + light + " --out " + out + " --max-memory lots",
       "--max-memory"},
      // Endless devices as inputs: refused, not read forever.
      {"build /dev/zero --light " + light + " --out " + out, "/dev/zero: is not a regular file"},
      {"build " + dir.file("d.pfm") + " --light /dev/zero --out " + out,
       "/dev/zero: is larger than 64 MiB"},
      {"build " + dir.file("d.pfm") + " --light " + dir.path() + " --out " + out, "is a directory"},
#ifdef LIGHTVOL_TEST_SHADOWMAP
      // The size is checked against the budget before the scene is read.
      {"shadowmap " + dir.file("no_scene.ply") + " --light " + light + " --size 4096 --out " +
           dir.file("s.exr") + " --max-memory 100M",
       light},
#endif
  };
  for (const Case& c : cases) {
    const test::CommandResult r = test::run_lightvol(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_TRUE(contains(r.err, "lightvol: ")) << r.err;
    EXPECT_TRUE(contains(r.err, c.names)) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  std::ifstream kept(existing);
  std::string text((std::istreambuf_iterator<char>(kept)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "keep me");
}

}  // namespace
}  // namespace lightvol
