#include "handeye_covariance/session/session_config.h"

#include <type_traits>

#include "handeye_covariance/io/files.h"

namespace handeye {

void read_session_config(const std::string& path, SessionConfig& config) {
  io::SettingsFile file(path);
  for_each_setting(config, [&](const char* key, auto& member, double scale) {
    using T = std::decay_t<decltype(member)>;
    if constexpr (std::is_same_v<T, double>) {
      if (const auto v = file.value<double>(key)) member = *v * scale;
    } else if constexpr (std::is_same_v<T, Setup>) {
      if (const auto v = file.value<bool>(key)) member = setup_from_eye_on_hand(*v);
    } else {
      if (const auto v = file.value<T>(key)) member = *v;
    }
  });
  file.refuse_unknown("use the node's parameter names (config/calibration_defaults.yaml, launch/calibrate.launch)");
}

}  // namespace handeye
