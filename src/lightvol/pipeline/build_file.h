// A light volume file from a light's depth images, end to end: what `lightvol build` does, one
// call. An engine's tool, `lightvol build`, `batch` and `demo` all make their volume files here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lightvol/check/check.h>
#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/core/stages.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/build_volume.h>

namespace lightvol {

struct BuildFileOptions {
  std::vector<std::string> depth_paths;  // the light's depth input (read_shadow_maps)
  std::string light_path;                // the light description (load_light)
  std::string out_path;                  // the volume; its extension picks the format (write_mesh)
  // The JSON report (docs/formats.md, "Build reports"), written beside the volume, committed with
  // it; "" for none. Named by a descriptor ("-"), it is written through (core/atomic_file.h).
  std::string report_path;
  bool make_report = false;  // the report's text in BuildFileResult::report even without a file
  // A medium description, recorded in a GLB beside the light (medium_record_json); "" for none.
  std::string medium_path;
  std::string channel;        // DepthReadOptions::channel
  BuildVolumeOptions volume;  // frame, grid, adaptive bound (light_source: light_path)
  bool check = true;          // refuse a volume that fails check_volume_linear, with the light
  bool ascii = false;         // ExportOptions::ascii
  bool draco = false;         // ExportOptions::draco
  int draco_bits = 16;        // ExportOptions::draco_bits
  bool keep_mesh = false;     // the volume in BuildFileResult::mesh (not when streamed)
  // The light's and the medium's bytes when the caller has read them (a pipe is read once):
  // parsed instead of reading light_path and medium_path, which still name them.
  const std::string* light_text = nullptr;
  const std::string* medium_text = nullptr;
  // The light and its maps when the caller holds them (an engine, the demo): used instead of
  // reading light_path and depth_paths, which still name them in messages and the report.
  const Light* light = nullptr;
  const ShadowMaps* maps = nullptr;
};

// The seconds of each step of a build_volume_file call.
struct BuildStepSeconds {
  double read = 0;   // the light, the maps, the medium
  double wait = 0;   // admission (pipeline/build_job.h: until the build's memory fits)
  double build = 0;  // the volume
  double check = 0;  // the linear-time checks
  // The outputs, committed together; of a volume written while it was checked (a checked PLY, OBJ,
  // OFF or STL), the part of the write left when the check ended.
  double write = 0;
};

// What a build_volume_file call did.
struct BuildFileResult {
  Status status;  // success: the volume (and the report) written; else nothing was written
  std::vector<std::string> warnings;  // also in the report (a light whose aspect is not the map's)
  std::uint64_t vertices = 0, triangles = 0;
  double volume = 0;  // the volume's signed volume, world (or light-eye) units cubed
  BuildStepSeconds seconds;
  CheckReport check;   // the checks' report (options.check): valid, and its proof
  Mesh mesh;           // the volume, with options.keep_mesh
  std::string report;  // the report's JSON text (indent 2, no final line break), when made
};

// Reads the light and its depth input, builds the volume (build_volume; a static volume written
// unchecked to PLY is streamed into the file row by row, never held whole), checks it from the
// light (options.check), writes it atomically (a lossy encoding decoded again and checked, a GLB
// with its light in the volume's frame and the medium) and the report, both or neither. A checked
// PLY, OBJ, OFF or STL volume is written to its temporary (or spool) on a thread of its own while
// the check runs, and committed only once it has passed: a failing check leaves nothing behind.
// Each step is timed in `log` (its listeners may show them). Refused before anything is read: a
// path holding a control character, an output that is also an input (core/path.h file_identity), an
// output extension of no format. Errors name the file, and the BuildFileOptions member that names
// it.
BuildFileResult build_volume_file(const BuildFileOptions& options, StageLog& log);

}  // namespace lightvol
