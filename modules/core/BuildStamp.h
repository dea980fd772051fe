#pragma once
/// @file BuildStamp.h
/// @brief Which sources a binary was built from: "VERSION+HASH".
///
/// Every plugin and the app link their own copy (the caps_build_stamp
/// object library, hidden so each binary answers for itself). The module
/// manager refuses a plugin whose stamp differs from the app's: a plugin
/// left over from another build may disagree with the shared libraries
/// about the layout of every class they exchange.

namespace caps {

/// This binary's build stamp: the project version, '+', and the first 16 hex
/// digits of the SHA-256 of the source tree it was built from.
__attribute__((visibility("hidden"))) const char* buildStamp();

} // namespace caps
