#include "handeye_covariance/session/session_config.h"

#include <type_traits>

#include "handeye_covariance/io/files.h"

namespace handeye {

void read_session_config(const std::string& path, SessionConfig& config) {
  io::SettingsFile file(path);
  for_each_setting(config, [&](const char* key, auto& member, double scale) {
    using T = std::decay_t<decltype(member)>;
    if constexpr (std::is_same_v<T, double>) {
      if (const auto v = file.number(key)) member = *v * scale;
    } else if constexpr (std::is_same_v<T, Setup>) {
      if (const auto v = file.flag(key)) member = setup_from_eye_on_hand(*v);
    } else if constexpr (std::is_same_v<T, bool>) {
      if (const auto v = file.flag(key)) member = *v;
    } else if constexpr (std::is_same_v<T, int>) {
      if (const auto v = file.whole_number(key)) member = *v;
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (const auto v = file.text(key)) member = *v;
    } else {
      static_assert(std::is_same_v<T, std::vector<int>>, "a setting's type SettingsFile cannot read");
      if (const auto v = file.whole_numbers(key)) member = *v;
    }
  });
  file.refuse_unknown("use the node's parameter names (config/calibration_defaults.yaml, launch/calibrate.launch)");
}

}  // namespace handeye
