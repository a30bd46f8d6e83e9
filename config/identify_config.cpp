// Reader of the `identify:` section (config/identify_config.hpp).
#include "config/identify_config.hpp"

#include "config/config_reader.hpp"

namespace rigctl {

IdentifyConfig read_identify(ConfigReader r) {
  IdentifyConfig c;
  if (r.has("excitation")) c.excitation = r.kind<ExcitationKind>("excitation");
  if (r.has("band_hz")) {
    const auto band = r.numbers("band_hz", 2, 2, 1e-3, 1e4);
    if (!(band[0] < band[1])) r.fail("band_hz", "must be [low, high] with low < high");
    c.band_min_hz = band[0];
    c.band_max_hz = band[1];
  }
  if (r.has("amplitude")) c.amplitude = r.number("amplitude", 0.0, 10.0);
  if (r.has("duration_s")) c.duration_s = r.number("duration_s", 0.1, 3600.0);
  if (r.has("resolution_hz")) c.resolution_hz = r.number("resolution_hz", 1e-3, 100.0);
  if (r.has("operating_point")) c.operating_point = r.number("operating_point", -10.0, 10.0);
  if (r.has("settle_s")) c.settle_s = r.number("settle_s", 0.0, 600.0);
  if (c.band_min_hz < c.resolution_hz) {
    r.fail("band_hz", "the band's low end must be at least one resolution step (resolution_hz) above 0");
  }
  r.reject_unknown_keys();
  return c;
}

}  // namespace rigctl
