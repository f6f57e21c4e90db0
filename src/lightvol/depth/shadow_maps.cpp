#include <utility>

#include <lightvol/depth/shadow_maps.h>

namespace lightvol {

ShadowMaps ShadowMaps::planar(DepthImage image, std::string source) {
  ShadowMaps maps;
  maps.image = std::move(image);
  maps.source = std::move(source);
  return maps;
}

ShadowMaps ShadowMaps::faces(CubeFaces cube) {
  ShadowMaps maps;
  maps.omni = true;
  maps.cube = std::move(cube);
  return maps;
}

std::vector<DepthImage> ShadowMaps::images() const {
  if (!omni) return {image};
  return {cube.faces.begin(), cube.faces.end()};
}

std::vector<std::string> ShadowMaps::sources() const {
  if (!omni) return {source};
  return {cube.sources.begin(), cube.sources.end()};
}

Result<ShadowMaps> read_shadow_maps(const Light& light, const std::vector<std::string>& paths,
                                    const DepthReadOptions& options) {
  if (light.type == LightType::omni) {
    Result<CubeFaces> cube = read_cube_faces(paths, options);
    if (!cube) return cube.error();
    return ShadowMaps::faces(std::move(*cube));
  }
  if (paths.size() != 1)
    return Error{"a " + std::string(to_string(light.type)) + " light takes one depth image, got " +
                 std::to_string(paths.size())};
  Result<DepthImage> image = read_depth_image(paths.front(), options);
  if (!image) return image.error();
  return ShadowMaps::planar(std::move(*image), paths.front());
}

Result<std::vector<std::string>> write_shadow_maps(const std::string& path,
                                                   const ShadowMaps& maps) {
  const bool has_face = path.find("{face}") != std::string::npos;
  if (has_face && !maps.omni) return Error{path + ": {face} applies to omni lights only"};
  std::vector<std::string> written;
  if (!maps.omni || !has_face) {
    if (Status s = write_depth_image(path, maps.omni ? stack_cube_faces(maps.cube) : maps.image);
        !s)
      return s.error();
    written.push_back(path);
    return written;
  }
  for (int face = 0; face < kOmniFaces; ++face) {
    const std::string face_path = expand_face_pattern(path, face);
    if (Status s = write_depth_image(face_path, maps.cube.faces[static_cast<std::size_t>(face)]);
        !s)
      return s.error();
    written.push_back(face_path);
  }
  return written;
}

}  // namespace lightvol
