#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <new>
#include <optional>
#include <system_error>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/check/check.h>
#include <lightvol/core/atomic_file.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/mesh.h>
#include <lightvol/core/path.h>
#include <lightvol/core/text.h>
#include <lightvol/core/text_file.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/io/mesh_format.h>
#include <lightvol/light/light.h>
#include <lightvol/pipeline/build_file.h>
#include <lightvol/pipeline/detail/build_hooks.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {
namespace {

// How messages name each path option (the CLI says the flag that sets it).
constexpr const char* kLightPath = "BuildFileOptions::light_path";
constexpr const char* kOutPath = "BuildFileOptions::out_path";
constexpr const char* kReportPath = "BuildFileOptions::report_path";
constexpr const char* kMediumPath = "BuildFileOptions::medium_path";

// Why `o` may not run as given, before anything is read: a path holding a control character (a NUL
// would end it early, a line break split a message), an output that would replace an input
// (compared by identity: the same inode, or the same new path).
Status check_paths(const BuildFileOptions& o) {
  std::vector<std::pair<std::string, std::string>> paths = {{kLightPath, o.light_path},
                                                            {kOutPath, o.out_path},
                                                            {kReportPath, o.report_path},
                                                            {kMediumPath, o.medium_path}};
  for (const std::string& p : o.depth_paths) paths.emplace_back("depth input", p);
  for (const auto& [name, path] : paths)
    if (const std::string where = control_character_in(path); !where.empty())
      return Error{name + ": " + where + " in the path; paths may not hold one"};
  std::vector<std::pair<std::string, std::string>> inputs = {{kLightPath, o.light_path},
                                                             {kMediumPath, o.medium_path}};
  for (const std::string& p : depth_input_files(o.depth_paths))
    inputs.emplace_back("depth input", p);
  for (const auto& [out_name, out] :
       {std::pair<std::string, std::string>{kOutPath, o.out_path}, {kReportPath, o.report_path}}) {
    if (out.empty()) continue;
    const std::string identity = file_identity(out);
    for (const auto& [in_name, in] : inputs)
      if (!in.empty() && file_identity(in) == identity)
        return Error{out_name + " " + out + ": is also the " + in_name + " " + in +
                     "; an output may not replace an input"};
  }
  return {};
}

std::string json_text(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

// What the report says of the volume written (a streamed volume is not held: its stream tallies
// these).
struct VolumeSummary {
  std::uint64_t vertices = 0, triangles = 0;
  Bounds bounds;
  double volume = 0;
};

// The report of a finished build (docs/formats.md, "Build reports").
nlohmann::json build_report(const BuildFileOptions& o, const Light& light, const ShadowMaps& maps,
                            const VolumeSummary& mesh, const AdaptiveReport* adaptive,
                            const StageLog& log, const std::vector<std::string>& warnings,
                            const nlohmann::json& extra) {
  nlohmann::json stages = nlohmann::json::array();
  for (const StageRecord& s : log.stages())
    stages.push_back(
        {{"name", s.name}, {"seconds", s.seconds}, {"peak_memory_bytes", s.peak_memory_bytes}});
  nlohmann::json report = {
      {"inputs", o.depth_paths},
      {"light",
       {{"path", o.light_path},
        {"type", to_string(light.type)},
        {"depth", to_string(light.depth)}}},
      {"output", o.out_path},
      {"space", o.volume.space == Space::light ? "light" : "world"},
      {"width", maps.width()},
      {"height", maps.height()},
      {"mode", adaptive ? "adaptive" : "static"},
      {"vertices", mesh.vertices},
      {"triangles", mesh.triangles},
      {"bounds", {{"min", mesh.bounds.min}, {"max", mesh.bounds.max}}},
      {"volume", mesh.volume},
      {"stages", stages},
      {"total_seconds", log.total_seconds()},
      {"peak_memory_bytes", peak_memory_bytes()},
      {"warnings", warnings},
  };
  for (const auto& [key, value] : extra.items()) report[key] = value;
  if (!adaptive) return report;
  const AdaptiveReport& a = *adaptive;
  const AdaptiveOptions& ao = o.volume.adaptive;
  const bool laplacian = ao.refinement == Refinement::laplacian;
  report["adaptive"] = {
      {"refine", laplacian ? "laplacian" : "error"},
      {"tessellation",
       !laplacian && ao.tessellation != Tessellation::quadtree ? "collapse" : "quadtree"},
      {"max_error", laplacian ? nlohmann::json(nullptr) : nlohmann::json(ao.max_error)},
      {"threshold", laplacian ? nlohmann::json(ao.threshold) : nlohmann::json(nullptr)},
      {"max_error_reached", a.max_error_reached},
      {"grid_triangles", a.grid_triangles},
      {"quadtree_triangles", a.quadtree_triangles},
      {"collapses", a.collapses},
      {"min_angle_degrees", a.min_angle_degrees},
      {"min_area_texels", a.min_area},
      {"leaves", a.leaves},
      {"fixup_rounds", a.fixup_rounds},
      {"seconds",
       {{"error_pyramid", a.pyramid_seconds},
        {"balance", a.balance_seconds},
        {"emit", a.emit_seconds},
        {"collapse", a.collapse_seconds},
        {"measure", a.measure_seconds},
        {"assemble", a.assemble_seconds}}}};
  return report;
}

// The memory a build in these modes takes (the budget's estimate, checked as the map is read).
BuildMemory memory_mode(const BuildFileOptions& o, bool adaptive, bool streamed) {
  if (adaptive) return BuildMemory::adaptive;
  if (streamed) return BuildMemory::static_streamed;
  return o.check ? BuildMemory::static_checked : BuildMemory::static_unchecked;
}

// Every file a build writes is written here, and only here: the volume (by `write_volume`, timed
// as the step `step`), then the report, made by `report_of` once the volume is written (it records
// that step's time). Both are committed together, or neither is.
//
// With `check` (a checked build whose writer streams the held mesh to its file), the volume is
// written on a thread of its own while `check` runs on this one (it times itself as the stage
// "checking"); the step `step` then times only the part of the write left when the check ends.
// Both only read the mesh. A check that fails returns its error once the writer has finished: the
// transaction removes what it staged (a file's temporary, a stream's spool), nothing is written,
// as when the check ran first.
Status write_outputs(const BuildFileOptions& o, const std::string& step,
                     const std::function<Status()>& write_volume, StageLog& log,
                     const std::function<nlohmann::json()>& report_of,
                     const detail::BuildFileHooks& hooks, BuildFileResult& r,
                     const std::function<Status()>& check = nullptr) {
  OutputTransaction outputs;
  if (check) {
    Status written;
    bool writing = false;
    {
      // Joined before this scope ends, however it ends (a check that throws unwinds through it).
      struct Joined {
        std::thread thread;
        ~Joined() {
          if (thread.joinable()) thread.join();
        }
      } writer;
      try {
        writer.thread = std::thread([&] {
          const OutputTransaction::Writer staged(outputs);
          try {
            written = write_volume();
          } catch (const std::bad_alloc&) {
            written = Error{o.out_path + ": out of memory while writing", ErrorKind::io};
          } catch (const std::exception& e) {
            written = Error{o.out_path + ": " + e.what(), ErrorKind::io};
          }
        });
        writing = true;
      } catch (const std::system_error&) {
        // No thread to be had: the volume is written after the check, on this one.
      }
      if (Status checked = check(); !checked) return checked;
      log.begin(step);
    }
    if (!writing) written = write_volume();
    if (!written) return written;
  } else {
    log.begin(step);
    if (Status s = write_volume(); !s) return s;
  }
  log.end();
  r.seconds.write = log.last_seconds();
  nlohmann::json report = report_of();
  if (hooks.volume_written) {
    const std::string file = outputs.staged_file(o.out_path);
    if (file.empty()) return Error{o.out_path + ": the volume was not written to a file"};
    Result<nlohmann::json> keys = hooks.volume_written(file);
    if (!keys) return keys.error();
    for (const auto& [key, value] : keys->items()) report[key] = value;
  }
  r.report = json_text(report);
  if (!o.report_path.empty())
    if (Status s = write_bytes_atomically(o.report_path, r.report + "\n"); !s) return s;
  return outputs.commit();
}

}  // namespace

BuildFileResult build_volume_file(const BuildFileOptions& o, StageLog& log) {
  return detail::build_volume_file(o, log, {});
}

BuildFileResult detail::build_volume_file(const BuildFileOptions& o, StageLog& log,
                                          const BuildFileHooks& hooks) {
  BuildFileResult r;
  auto failed = [&r](Error error) {
    r.status = std::move(error);
    return r;
  };
  if (Status s = check_paths(o); !s) return failed(s.error());
  Result<MeshFormat> format = mesh_format_from_path(o.out_path);
  if (!format) return failed(format.error());
  BuildVolumeOptions options = o.volume;
  if (!o.light_path.empty()) options.light_source = o.light_path;
  options.adaptive.measure = o.make_report || !o.report_path.empty();  // the reached error
  const bool adaptive = options.grid == VolumeGrid::adaptive;

  // ---- read: the light, the medium, the maps
  // -----------------------------------------------------
  Result<Light> light = o.light ? Result<Light>(*o.light) : Error{};
  if (!o.light) {
    log.begin("reading " + o.light_path);
    light = o.light_text ? parse_light(*o.light_text, o.light_path) : load_light(o.light_path);
    if (!light) return failed(light.error());
    log.end();
    r.seconds.read += log.last_seconds();
  }
  std::string medium;
  if (!o.medium_path.empty()) {
    Result<std::string> text = o.medium_text ? Result<std::string>(*o.medium_text)
                                             : read_text_file(o.medium_path, "medium description");
    if (!text) return failed(text.error());
    Result<std::string> record = medium_record_json(*text, o.medium_path);
    if (!record) return failed(record.error());
    medium = std::move(*record);
  }

  const bool omni = light->type == LightType::omni;
  // A static volume written unchecked to PLY is streamed: built row by row into the file.
  const bool streamed = !adaptive && !omni && !o.check && *format == MeshFormat::ply;
  DepthReadOptions read_options;
  read_options.channel = o.channel;
  read_options.memory = memory_mode(o, adaptive, streamed);
  // A static volume held whole: its buffers reserved and mapped on a thread of their own while the
  // map is read (lightvol-image's start and decoding), when lightvol's own look at the header
  // tells the map's size and the budget allows the build (the read checks it again from the
  // decoder's header). Not in a batch, whose jobs wait for memory before they build.
  Mesh storage;
  std::thread reserving;
  struct Joined {
    std::thread& thread;
    ~Joined() {
      if (thread.joinable()) thread.join();
    }
  } joined{reserving};
  if (!adaptive && !omni && !streamed && !o.maps && o.depth_paths.size() == 1 &&
      !hooks.before_build) {
    const std::optional<std::array<int, 2>> size = peek_image_size(o.depth_paths.front());
    if (size && (*size)[0] >= 2 && (*size)[1] >= 2 &&
        std::int64_t{(*size)[0]} * (*size)[1] < (std::int64_t{1} << 31) &&
        build_memory_bytes(read_options.memory, (*size)[0], (*size)[1]) <= memory_budget()) {
      try {
        reserving = std::thread([&storage, type = light->type, w = (*size)[0], h = (*size)[1]] {
          try {
            storage = reserve_static_volume(type, w, h);
          } catch (const std::bad_alloc&) {
            storage = Mesh{};  // the build allocates (and reports) as it would have
          }
        });
      } catch (const std::system_error&) {
        // No thread to be had: the build maps its buffers itself.
      }
    }
  }
  Result<ShadowMaps> read = Error{};
  if (!o.maps) {
    log.begin(omni ? "reading omni faces" : "reading " + o.depth_paths.front());
    read = read_shadow_maps(*light, o.depth_paths, read_options);
    if (!read) return failed(read.error());
    log.end(std::to_string(read->width()) + "x" + std::to_string(read->height()) +
            (omni ? " x 6" : ""));
    r.seconds.read += log.last_seconds();
  }
  const ShadowMaps* const maps = o.maps ? o.maps : &*read;
  const std::string map_name = o.depth_paths.empty() ? maps->source : o.depth_paths.front();
  if (const std::string note = omni ? "" : aspect_mismatch(*light, maps->width(), maps->height());
      !note.empty())
    r.warnings.push_back(map_name + ": " + note);

  if (hooks.after_read)
    if (Status s = hooks.after_read(); !s) return failed(s.error());
  if (hooks.before_build) {
    const auto waited_from = std::chrono::steady_clock::now();
    hooks.before_build(*maps, read_options.memory);
    r.seconds.wait =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - waited_from).count();
  }

  ExportOptions eo;
  eo.ascii = o.ascii;
  VolumeSummary summary;
  const std::function<nlohmann::json()> report_of_static = [&] {
    return build_report(o, *light, *maps, summary, nullptr, log, r.warnings, hooks.extra_report);
  };
  if (streamed) {
    // Never held whole (its memory does not grow with the mesh); still refused, with nothing
    // written, when float32 cannot hold it.
    StaticVolumeStream stream(*light, maps->image, VolumeOptions{options.space}, maps->source,
                              o.light_path);
    const auto write = [&]() -> Status {
      if (Status s = write_mesh_stream(o.out_path, stream, eo); !s) return s;
      summary = {stream.num_vertices(), stream.num_triangles(), stream.bounds(), stream.volume()};
      return {};
    };
    if (Status s = write_outputs(o, "building the static volume into " + o.out_path, write, log,
                                 report_of_static, hooks, r);
        !s)
      return failed(s.error());
    r.vertices = summary.vertices;
    r.triangles = summary.triangles;
    r.volume = summary.volume;
    return r;
  }

  // ---- build, check
  // ------------------------------------------------------------------------------
  log.begin(std::string("building ") + (adaptive ? "adaptive " : "static ") +
            (omni ? "omni " : "") + "volume");
  AdaptiveReport adaptive_report;
  if (reserving.joinable()) reserving.join();
  Result<Mesh> mesh = build_volume(*light, *maps, options, &adaptive_report, std::move(storage));
  if (!mesh) return failed(mesh.error());
  log.end(thousands(mesh->num_triangles()) + " triangles");
  r.seconds.build = log.last_seconds();

  const Light frame_light = light_in_space(*light, options.space);
  const auto check = [&]() -> Status {
    log.begin("checking");
    r.check = check_volume_linear(*mesh, &frame_light);
    if (!r.check.valid())
      return Error{o.out_path + ": the built volume fails its checks, nothing written: " +
                       r.check.first_failure(),
                   ErrorKind::unsound};
    log.end("valid");
    r.seconds.check = log.last_seconds();
    // The check found the bounds and the signed volume: bounding_box's and signed_volume's to the
    // bit (the same minima and maxima; the same sums in the same order), not measured again.
    summary = {mesh->num_vertices(), mesh->num_triangles(), r.check.bounds, r.check.volume};
    return {};
  };
  // A writer that streams the held mesh to the file writes while the check runs (write_outputs);
  // a Draco or GLB encoding is made whole in memory (and a lossy one checked again), so it waits
  // for the check rather than add its bytes to the check's memory and its CPU to the check's.
  const bool write_while_checking =
      o.check && *format != MeshFormat::drc && *format != MeshFormat::glb;
  if (o.check && hooks.before_check) hooks.before_check(*mesh);

  // ---- write
  // -------------------------------------------------------------------------------------
  eo.draco = o.draco;
  eo.draco_bits = o.draco_bits;
  if (o.check) eo.light = &frame_light;  // a lossy encoding must stay sound seen from the light
  eo.glb.light = &frame_light;           // a GLB carries its light, in the volume's frame
  eo.glb.medium_json = medium;
  const auto report_of = [&] {
    return build_report(o, *light, *maps, summary, adaptive ? &adaptive_report : nullptr, log,
                        r.warnings, hooks.extra_report);
  };
  if (!o.check)
    summary = {mesh->num_vertices(), mesh->num_triangles(), bounding_box(*mesh),
               signed_volume(*mesh)};
  else if (!write_while_checking)
    if (Status s = check(); !s) return failed(s.error());
  if (Status s = write_outputs(
          o, "writing " + o.out_path, [&] { return write_mesh(o.out_path, *mesh, eo); }, log,
          report_of, hooks, r, write_while_checking ? std::function<Status()>(check) : nullptr);
      !s)
    return failed(s.error());
  r.vertices = summary.vertices;
  r.triangles = summary.triangles;
  r.volume = summary.volume;
  if (o.keep_mesh) r.mesh = std::move(*mesh);
  return r;
}

}  // namespace lightvol
