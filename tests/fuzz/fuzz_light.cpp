// Fuzz target: the light JSON parser. Any input must give a Light or an Error naming the source.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include <lightvol/core/check.h>
#include <lightvol/light/light.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const lightvol::Result<lightvol::Light> light = lightvol::parse_light(text, "fuzz.json");
  if (!light) LV_CHECK(light.error().message.rfind("fuzz.json", 0) == 0);
  return 0;
}
