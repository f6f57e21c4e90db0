// Fuzz target: the JSON descriptions: light (build, check, stats, shadowmap), medium and camera
// (render). Any input must give a value or an Error naming the source; a light that parses must
// also unproject (its matrices invert).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/check.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>

namespace {

template <class T>
void require_named(const lightvol::Result<T>& result) {
  if (!result) LV_CHECK(result.error().message.rfind("fuzz.json", 0) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const lightvol::Result<lightvol::Light> light = lightvol::parse_light(text, "fuzz.json");
  require_named(light);
  if (light) {
    const lightvol::Unprojector unproject(*light, 3, 2, 0, lightvol::Space::world);
    (void)unproject.near_point(0, 0);
  }
  require_named(lightvol::parse_medium(text, "fuzz.json"));
  require_named(lightvol::parse_camera(text, "fuzz.json"));
  return 0;
}
