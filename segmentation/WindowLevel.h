#pragma once
/// @file WindowLevel.h
/// @brief CT display windows (width and centre in HU), as radiographers name them.

#include <array>
#include <string_view>

namespace caps::seg {

struct WindowLevel
{
  std::string_view name;
  double window; ///< width in HU
  double level;  ///< centre in HU
};

/// The usual head and neck CT windows.
inline constexpr std::array<WindowLevel, 5> kWindowPresets = {{
  {"Soft tissue", 400.0, 40.0},
  {"Bone", 2000.0, 500.0},
  {"Brain", 80.0, 40.0},
  {"Skin / air", 1000.0, -400.0},
  {"Full range", 4096.0, 1024.0},
}};

} // namespace caps::seg
