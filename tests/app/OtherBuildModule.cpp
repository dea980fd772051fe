// A plugin of the right module API built from other sources: a build stamp
// that is not this build's (a plugin left over from an older build).
#include "modules/core/Module.h"

extern "C" __attribute__((visibility("default"))) int caps_module_api_version()
{
  return caps::kModuleApiVersion;
}
extern "C" __attribute__((visibility("default"))) const char* caps_module_build_stamp()
{
  return "0.0.0+0123456789abcdef";
}
extern "C" __attribute__((visibility("default"))) caps::Module* caps_create_module()
{
  return nullptr;
}
