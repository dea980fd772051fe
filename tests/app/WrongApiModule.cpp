// A plugin built against another module API version.
#include "modules/core/Module.h"

extern "C" __attribute__((visibility("default"))) int caps_module_api_version()
{
  return caps::kModuleApiVersion + 100;
}
extern "C" __attribute__((visibility("default"))) caps::Module* caps_create_module()
{
  return nullptr;
}
