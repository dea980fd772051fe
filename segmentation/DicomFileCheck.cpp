#include "segmentation/DicomFileCheck.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

namespace caps::seg {
namespace {

constexpr uint32_t kUndefinedLength = 0xFFFFFFFF;
constexpr int kMaxDepth = 32; // nested sequences deeper than this are not real data

struct Damage
{
  std::string what;
};

std::string tagText(uint16_t group, uint16_t element)
{
  char text[16];
  std::snprintf(text, sizeof text, "(%04X,%04X)", group, element);
  return text;
}

// Walks a little-endian DICOM byte stream; throws Damage where it breaks.
class Walker
{
public:
  explicit Walker(const std::vector<uint8_t>& bytes) : bytes_(bytes) {}

  size_t position() const { return pos_; }
  void seek(size_t pos) { pos_ = pos; }
  bool atEnd() const { return pos_ >= bytes_.size(); }
  size_t size() const { return bytes_.size(); }

  uint16_t peek16(size_t offset) const
  {
    return static_cast<uint16_t>(bytes_[pos_ + offset] | bytes_[pos_ + offset + 1] << 8);
  }

  // Reads one element (and whatever it contains). Returns its tag and, for
  // short values, its value as text (used for the transfer syntax).
  void element(bool explicitVr, int depth, uint16_t& group, uint16_t& elem, std::string& value)
  {
    need(8, "an element header");
    group = read16();
    elem = read16();
    uint32_t length = 0;
    std::string vr;
    const bool itemTag = group == 0xFFFE;
    if (explicitVr && !itemTag)
    {
      vr = {static_cast<char>(bytes_[pos_]), static_cast<char>(bytes_[pos_ + 1])};
      if (!(std::isupper(static_cast<unsigned char>(vr[0])) && std::isupper(static_cast<unsigned char>(vr[1]))))
        throw Damage{"element " + tagText(group, elem) + " at byte " + std::to_string(pos_ - 4) +
                     " has no valid value representation"};
      pos_ += 2;
      static const char* longForms[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ", "SV", "UC", "UN", "UR", "UT", "UV"};
      bool longForm = false;
      for (const char* l : longForms)
        longForm = longForm || vr == l;
      if (longForm)
      {
        need(6, "the length of element " + tagText(group, elem));
        pos_ += 2;
        length = read32();
      }
      else
        length = read16();
    }
    else
    {
      length = read32();
    }
    if (length == kUndefinedLength)
    {
      if (depth >= kMaxDepth)
        throw Damage{"sequences nested deeper than " + std::to_string(kMaxDepth) + " levels"};
      if (itemTag && elem == 0xE000)
        itemDataSet(explicitVr, depth + 1, group, elem);
      else
        items(explicitVr, depth + 1, group, elem);
      return;
    }
    if (length > bytes_.size() - pos_)
      throw Damage{"the file is cut short: element " + tagText(group, elem) + " at byte " + std::to_string(pos_) +
                   " needs " + std::to_string(length) + " bytes but only " + std::to_string(bytes_.size() - pos_) +
                   " remain"};
    if (vr == "SQ" || (!explicitVr && length > 0 && looksLikeItem()))
    {
      // A defined-length sequence: walk its items inside their bounds.
      const size_t end = pos_ + length;
      while (pos_ < end)
      {
        uint16_t g, e;
        std::string v;
        element(explicitVr, depth + 1, g, e, v);
      }
      if (pos_ != end)
        throw Damage{"sequence " + tagText(group, elem) + " overruns its declared length"};
      return;
    }
    if (itemTag && elem == 0xE000)
    {
      // A defined-length item: a nested data set.
      const size_t end = pos_ + length;
      while (pos_ < end)
      {
        uint16_t g, e;
        std::string v;
        element(explicitVr, depth + 1, g, e, v);
      }
      return;
    }
    if (length <= 64)
      value.assign(reinterpret_cast<const char*>(&bytes_[pos_]), length);
    pos_ += length;
  }

private:
  void need(size_t n, const std::string& what) const
  {
    if (bytes_.size() - pos_ < n)
      throw Damage{"the file is cut short at byte " + std::to_string(bytes_.size()) + ", inside " + what};
  }
  uint16_t read16()
  {
    const uint16_t v = peek16(0);
    pos_ += 2;
    return v;
  }
  uint32_t read32()
  {
    need(4, "an element length");
    const uint32_t v = static_cast<uint32_t>(bytes_[pos_]) | bytes_[pos_ + 1] << 8 | bytes_[pos_ + 2] << 16 |
                       static_cast<uint32_t>(bytes_[pos_ + 3]) << 24;
    pos_ += 4;
    return v;
  }
  bool looksLikeItem() const { return bytes_.size() - pos_ >= 4 && peek16(0) == 0xFFFE && peek16(2) == 0xE000; }
  // Items of an undefined-length sequence (or pixel data fragments), up to
  // the sequence delimiter.
  void items(bool explicitVr, int depth, uint16_t group, uint16_t elem)
  {
    while (true)
    {
      if (bytes_.size() - pos_ < 8)
        throw Damage{"the file is cut short at byte " + std::to_string(bytes_.size()) + ", inside the sequence " +
                     tagText(group, elem)};
      const uint16_t g = read16(), e = read16();
      const uint32_t length = read32();
      if (g != 0xFFFE)
        throw Damage{"sequence " + tagText(group, elem) + " holds a non-item element " + tagText(g, e) + " at byte " +
                     std::to_string(pos_ - 8)};
      if (e == 0xE0DD) // sequence delimiter
        return;
      if (e != 0xE000)
        throw Damage{"unexpected delimiter " + tagText(g, e) + " at byte " + std::to_string(pos_ - 8)};
      if (length == kUndefinedLength)
        itemDataSet(explicitVr, depth, group, elem);
      else
      {
        if (length > bytes_.size() - pos_)
          throw Damage{"the file is cut short: an item of " + tagText(group, elem) + " at byte " +
                       std::to_string(pos_) + " needs " + std::to_string(length) + " bytes but only " +
                       std::to_string(bytes_.size() - pos_) + " remain"};
        // Pixel data fragments are opaque; sequence items are data sets.
        if (!(group == 0x7FE0 && elem == 0x0010))
        {
          const size_t end = pos_ + length;
          while (pos_ < end)
          {
            uint16_t ig, ie;
            std::string v;
            element(explicitVr, depth + 1, ig, ie, v);
          }
        }
        else
          pos_ += length;
      }
    }
  }

  // An item of undefined length: a data set up to the item delimiter.
  void itemDataSet(bool explicitVr, int depth, uint16_t group, uint16_t elem)
  {
    while (true)
    {
      if (bytes_.size() - pos_ < 8)
        throw Damage{"the file is cut short at byte " + std::to_string(bytes_.size()) + ", inside an item of " +
                     tagText(group, elem)};
      if (peek16(0) == 0xFFFE && peek16(2) == 0xE00D)
      {
        pos_ += 8;
        return;
      }
      uint16_t ig, ie;
      std::string v;
      element(explicitVr, depth + 1, ig, ie, v);
    }
  }

  const std::vector<uint8_t>& bytes_;
  size_t pos_ = 0;
};

std::string trimUid(std::string uid)
{
  while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' '))
    uid.pop_back();
  return uid;
}

} // namespace

DicomFileCheck checkDicomFile(const std::filesystem::path& file)
{
  std::ifstream in(file, std::ios::binary);
  if (!in)
    return {DicomFileKind::NotDicom, "cannot be opened"};
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Walker walker(bytes);
  const bool part10 = bytes.size() >= 132 && std::memcmp(&bytes[128], "DICM", 4) == 0;
  std::string transferSyntax;
  bool explicitVr = true;
  try
  {
    if (part10)
    {
      walker.seek(132);
      // The meta group is always explicit VR little endian.
      while (!walker.atEnd() && walker.size() - walker.position() >= 2 && walker.peek16(0) == 0x0002)
      {
        uint16_t g, e;
        std::string value;
        walker.element(true, 0, g, e, value);
        if (e == 0x0010)
          transferSyntax = trimUid(value);
      }
      if (transferSyntax.empty())
        throw Damage{"the file meta information names no transfer syntax"};
      if (transferSyntax == "1.2.840.10008.1.2.2" || transferSyntax == "1.2.840.10008.1.2.1.99")
        return {DicomFileKind::Sound, {}}; // big endian or deflated: not walked here
      explicitVr = transferSyntax != "1.2.840.10008.1.2";
    }
    else
    {
      // A raw data set without the Part 10 header: it must start with a
      // group 0008 element to be taken for DICOM at all.
      if (bytes.size() < 8 || walker.peek16(0) != 0x0008)
        return {DicomFileKind::NotDicom, {}};
      explicitVr = std::isupper(bytes[4]) && std::isupper(bytes[5]);
    }
    bool pixelData = false;
    while (!walker.atEnd())
    {
      uint16_t g, e;
      std::string value;
      walker.element(explicitVr, 0, g, e, value);
      pixelData = pixelData || (g == 0x7FE0 && e == 0x0010);
    }
    // A file cut exactly between two elements walks cleanly: only the
    // missing pixel data gives it away.
    if (!pixelData)
      throw Damage{"it holds no pixel data: it is cut short after byte " + std::to_string(bytes.size()) +
                   ", or is not an image slice"};
  }
  catch (const Damage& damage)
  {
    return {DicomFileKind::Damaged, damage.what};
  }
  return {DicomFileKind::Sound, {}};
}

} // namespace caps::seg
