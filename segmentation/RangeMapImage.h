#pragma once
/// @file RangeMapImage.h
/// @brief Range maps as 16-bit grey PNG and colour maps as RGB PNG, to edit in an
/// image program and read back (§3.2.1, §4.2.1: the thesis retouched Cyberware
/// range data in Photoshop).

#include <string>

#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

namespace caps::seg {

/// How r is stored in the 16-bit grey values g: g = 0 is NaN (no surface),
/// g in 1..65535 is r = offsetMm + stepMm · (g − 1). stepMm is the
/// quantisation step: a round trip changes r by at most stepMm / 2.
struct RangeMapImageEncoding
{
  double offsetMm = 0.0;
  double stepMm = 1.0;
};

/// The encoding that spans the map's finite range [rMin, rMax] with 65535
/// levels (stepMm = (rMax − rMin) / 65534; 1e-3 mm for a constant map).
RangeMapImageEncoding rangeMapImageEncoding(const RangeMap& map);

/// Write map as a 16-bit grey PNG, nθ wide and nz high, column i = θ_i, row
/// j = z_j with j = 0 (inferior) at the bottom of the picture so the head is
/// upright. The encoding and the frame (origin, direction, zMin, zMax) are
/// stored in PNG tEXt chunks (keys "CAPS:..."), so readRangeMapPng rebuilds the
/// map alone. @returns the encoding used. @throws std::runtime_error if it cannot write.
RangeMapImageEncoding writeRangeMapPng(const RangeMap& map, const std::string& path);
/// The same with a given encoding (values outside its range are clamped to 1..65535).
void writeRangeMapPng(const RangeMap& map, const std::string& path, const RangeMapImageEncoding& encoding);

/// Read a PNG written by writeRangeMapPng (possibly edited: any 8- or 16-bit
/// grey or colour PNG whose text chunks survived; colour is read as its first
/// channel). @throws std::runtime_error if the file is missing or the
/// CAPS text chunks are gone (use the overload with a frame and encoding).
RangeMap readRangeMapPng(const std::string& path);
/// Read with a known frame and encoding (for images whose text chunks an
/// editor dropped). @throws std::runtime_error if the size is not nθ × nz.
RangeMap readRangeMapPng(const std::string& path, const CylindricalFrame& frame, const RangeMapImageEncoding& encoding);
/// The encoding stored in a PNG's text chunks. @throws std::runtime_error if absent.
RangeMapImageEncoding readRangeMapImageEncoding(const std::string& path);

/// Write a colour map as an 8-bit RGB PNG, oriented like writeRangeMapPng.
void writeColourMapPng(const ColourMap& map, const std::string& path);
/// Read an RGB (or RGBA, or grey) PNG onto frame's grid.
/// @throws std::runtime_error if the file is missing or its size is not nθ × nz.
ColourMap readColourMapPng(const std::string& path, const CylindricalFrame& frame);

} // namespace caps::seg
