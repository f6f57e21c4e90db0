// An engine's tool through the installed library: builds the static volume of a 3×3 spot map and
// checks its counts, then writes it as a file with its report (pipeline/build_file.h, the call
// `lightvol build` makes) and checks what was written.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <lightvol/light/light.h>
#include <lightvol/pipeline/build_file.h>
#include <lightvol/volume/static_volume.h>

int main() {
  const lightvol::Result<lightvol::Light> light = lightvol::parse_light(
      R"({"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
          "fov_y_deg": 60, "near": 0.1, "far": 30, "depth": "linear"})",
      "consumer");
  if (!light) return std::fprintf(stderr, "%s\n", light.error().message.c_str()), 1;
  lightvol::DepthImage depth;
  depth.width = depth.height = 3;
  depth.values.assign(9, 2.0f);
  const lightvol::Result<lightvol::Mesh> mesh =
      lightvol::build_static_volume(*light, depth, {}, "3x3");
  if (!mesh || mesh->num_triangles() != 16 || mesh->num_vertices() != 10) {
    std::fprintf(stderr, "consumer: unexpected volume\n");
    return 1;
  }
  std::printf("consumer: %zu triangles, volume %.4f\n", mesh->num_triangles(),
              lightvol::signed_volume(*mesh));

  // The same volume as a file, checked before it is written, with its JSON report.
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("lightvol-consumer-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const lightvol::ShadowMaps maps = lightvol::ShadowMaps::planar(depth, "3x3");
  lightvol::BuildFileOptions options;
  options.light = &*light;
  options.maps = &maps;
  options.light_path = "consumer";
  options.out_path = (dir / "volume.glb").string();
  options.report_path = (dir / "volume.report.json").string();
  lightvol::StageLog log;
  const lightvol::BuildFileResult written = lightvol::build_volume_file(options, log);
  const bool ok = written.status && written.triangles == 16 && written.check.valid() &&
                  fs::file_size(options.out_path) > 0 &&
                  written.report.find("\"triangles\": 16") != std::string::npos &&
                  fs::file_size(options.report_path) == written.report.size() + 1;
  fs::remove_all(dir);
  if (!ok) {
    std::fprintf(
        stderr, "consumer: build_volume_file: %s\n",
        written.status ? "unexpected file or report" : written.status.error().message.c_str());
    return 1;
  }
  std::printf("consumer: wrote a checked GLB of %llu triangles and its report (%zu steps timed)\n",
              static_cast<unsigned long long>(written.triangles), log.stages().size());
  return 0;
}
