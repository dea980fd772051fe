#include "scene/NrrdIO.h"

#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkDataArray.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <climits>
#include <cmath>
#include <limits>
#include <fstream>
#include <locale>
#include <sstream>
#include <vector>

#include "scene/SceneError.h"

namespace caps {

namespace {

using std::filesystem::path;

struct TypeName
{
  int vtkType;
  const char* canonical;
  std::vector<std::string> aliases;
};

// NRRD type names (canonical first) and the VTK scalar type they map to.
const std::vector<TypeName>& typeNames()
{
  static const std::vector<TypeName> names{
    {VTK_SIGNED_CHAR, "signed char", {"signed char", "int8", "int8_t"}},
    {VTK_UNSIGNED_CHAR, "unsigned char", {"uchar", "unsigned char", "uint8", "uint8_t"}},
    {VTK_SHORT, "short", {"short", "short int", "signed short", "signed short int", "int16", "int16_t"}},
    {VTK_UNSIGNED_SHORT, "unsigned short", {"ushort", "unsigned short", "unsigned short int", "uint16", "uint16_t"}},
    {VTK_INT, "int", {"int", "signed int", "int32", "int32_t"}},
    {VTK_UNSIGNED_INT, "unsigned int", {"uint", "unsigned int", "uint32", "uint32_t"}},
    {VTK_FLOAT, "float", {"float"}},
    {VTK_DOUBLE, "double", {"double"}},
  };
  return names;
}

int sizeOfVtkType(int t)
{
  switch (t)
  {
  case VTK_SIGNED_CHAR:
  case VTK_UNSIGNED_CHAR:
    return 1;
  case VTK_SHORT:
  case VTK_UNSIGNED_SHORT:
    return 2;
  case VTK_INT:
  case VTK_UNSIGNED_INT:
  case VTK_FLOAT:
    return 4;
  case VTK_DOUBLE:
    return 8;
  }
  return 0;
}

std::string num(double v)
{
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.precision(17);
  s << v;
  return s.str();
}

std::string vec3(const double v[3])
{
  // Built with append, not "(" + ...: GCC 12 warns falsely (-Wrestrict) on the latter.
  std::string text(1, '(');
  text.append(num(v[0])).append(1, ',').append(num(v[1])).append(1, ',').append(num(v[2]));
  return text.append(1, ')');
}

// Writes header + data; gzip streams the data through zlib at the fast level
// (CT volumes compress well enough, and saving must stay quick).
void writeNrrd(const path& file, const std::string& header, const void* data, std::size_t bytes,
               NrrdIO::Encoding encoding)
{
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out)
    throw SceneError("cannot create " + file.string() + ": check the folder exists and is writable");
  out << header;
  if (encoding == NrrdIO::Encoding::Raw)
  {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  }
  else
  {
    z_stream zs{};
    if (deflateInit2(&zs, Z_BEST_SPEED, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
      throw SceneError("cannot start gzip compression for " + file.string());
    std::vector<unsigned char> buf(1 << 18);
    const auto* in = static_cast<const unsigned char*>(data);
    std::size_t left = bytes;
    int flush = Z_NO_FLUSH;
    do
    {
      if (zs.avail_in == 0 && flush != Z_FINISH)
      {
        const std::size_t chunk = std::min<std::size_t>(left, 1u << 30);
        zs.next_in = const_cast<unsigned char*>(in);
        zs.avail_in = static_cast<uInt>(chunk);
        in += chunk;
        left -= chunk;
        if (left == 0)
          flush = Z_FINISH;
      }
      zs.next_out = buf.data();
      zs.avail_out = static_cast<uInt>(buf.size());
      const int rc = deflate(&zs, flush);
      if (rc == Z_STREAM_ERROR)
      {
        deflateEnd(&zs);
        throw SceneError("gzip compression failed while writing " + file.string());
      }
      out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() - zs.avail_out));
      if (rc == Z_STREAM_END)
        break;
    } while (out);
    deflateEnd(&zs);
  }
  out.close();
  if (!out)
    throw SceneError("could not write " + file.string() + ": check free disk space and permissions");
}

// What the header says; the image data follow it in the file.
struct Nrrd
{
  int vtkType = 0;
  int dimension = 0;
  std::vector<std::size_t> sizes;
  bool hasSpace = false;
  std::array<double, 3> origin{0, 0, 0};
  std::array<std::array<double, 3>, 3> dirs{}; // dirs[axis] = direction * spacing
  std::vector<double> spacings;
  bool gzip = false;
  bool bigEndian = false;
  std::size_t bytes = 0; // of decoded image data: product of the sizes times the element size
};

std::string trim(std::string s)
{
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::vector<std::string> tokens(std::string text)
{
  for (char& c : text)
    if (c == '(' || c == ')' || c == ',')
      c = ' ';
  std::istringstream s(text);
  std::vector<std::string> out;
  std::string tok;
  while (s >> tok)
    out.push_back(tok);
  return out;
}

std::vector<double> numbers(const std::string& text, const path& file, const char* field)
{
  std::vector<double> v;
  for (const std::string& tok : tokens(text))
  {
    if (tok == "none" || tok == "nan" || tok == "NaN")
    {
      v.push_back(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    std::istringstream t(tok);
    t.imbue(std::locale::classic());
    double d;
    if (!(t >> d))
      throw SceneError(file.string() + ": cannot read the NRRD field '" + field + "': " + text);
    v.push_back(d);
  }
  return v;
}

// A whole non-negative decimal integer, or SceneError.
std::size_t integer(const std::string& tok, const path& file, const char* field)
{
  std::size_t v = 0;
  const char* end = tok.data() + tok.size();
  const auto [p, ec] = std::from_chars(tok.data(), end, v);
  if (ec != std::errc() || p != end || tok.empty())
    throw SceneError(file.string() + ": the NRRD field '" + field + "' must be a whole number, got '" + tok + "'");
  return v;
}

// Reads the gzip stream at the current position of @a in into dst[0, bytes).
void inflateInto(std::istream& in, char* dst, std::size_t bytes, const path& file)
{
  z_stream zs{};
  if (inflateInit2(&zs, 15 + 32) != Z_OK)
    throw SceneError("cannot start gzip decompression for " + file.string());
  std::vector<char> buf(1 << 18);
  std::size_t done = 0;
  int rc = Z_OK;
  while (done < bytes && rc != Z_STREAM_END)
  {
    if (zs.avail_in == 0)
    {
      in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
      if (in.gcount() <= 0)
        break;
      zs.next_in = reinterpret_cast<unsigned char*>(buf.data());
      zs.avail_in = static_cast<uInt>(in.gcount());
    }
    const std::size_t chunk = std::min<std::size_t>(bytes - done, 1u << 30);
    zs.next_out = reinterpret_cast<unsigned char*>(dst + done);
    zs.avail_out = static_cast<uInt>(chunk);
    rc = inflate(&zs, Z_NO_FLUSH);
    done += chunk - zs.avail_out;
    if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
    {
      inflateEnd(&zs);
      throw SceneError(file.string() + " is damaged (gzip data corrupt): restore it from a backup");
    }
  }
  inflateEnd(&zs);
  if (done != bytes)
    throw SceneError(file.string() + " is truncated (" + std::to_string(done) + " of " + std::to_string(bytes) +
                     " bytes of image data): restore it from a backup or re-save the scene");
}

// Parses the header of @a in line by line and leaves @a in at the image data.
// Checks that the file can hold what the sizes ask for before anyone allocates.
Nrrd readHeader(std::ifstream& in, const path& file)
{
  if (!in)
    throw SceneError("cannot open " + file.string() + ": the file is missing or unreadable");
  std::string line;
  if (!std::getline(in, line) || line.rfind("NRRD000", 0) != 0)
    throw SceneError(file.string() +
                     " is not a NRRD file (no NRRD000x magic): choose a .nrrd file written by CAPS, 3D Slicer or teem");

  Nrrd n;
  std::string encoding = "raw", endian = "little", space, spaceField;
  std::vector<double> dirs;
  bool ended = false;
  while (std::getline(in, line))
  {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    if (line.empty())
    {
      ended = true;
      break;
    }
    if (line[0] == '#')
      continue;
    if (line.find(":=") != std::string::npos)
      continue; // key/value pairs: not ours
    const auto colon = line.find(": ");
    if (colon == std::string::npos)
      throw SceneError(file.string() + ": malformed NRRD header line '" + line + "'");
    std::string key = trim(line.substr(0, colon)), value = trim(line.substr(colon + 2));
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    if (key == "type")
    {
      for (const auto& t : typeNames())
        if (std::find(t.aliases.begin(), t.aliases.end(), value) != t.aliases.end())
          n.vtkType = t.vtkType;
      if (!n.vtkType)
        throw SceneError(file.string() + ": NRRD type '" + value + "' is not supported by CAPS");
    }
    else if (key == "dimension")
    {
      n.dimension = static_cast<int>(std::min<std::size_t>(integer(value, file, "dimension"), 16));
    }
    else if (key == "sizes")
    {
      n.sizes.clear();
      for (const std::string& tok : tokens(value))
        n.sizes.push_back(integer(tok, file, "sizes"));
    }
    else if (key == "encoding")
    {
      encoding = value;
    }
    else if (key == "endian")
    {
      endian = value;
    }
    else if (key == "space")
    {
      space = value;
    }
    else if (key == "space dimension")
    {
      spaceField = key; // implied by "space"
    }
    else if (key == "space directions")
    {
      dirs = numbers(value, file, "space directions");
      spaceField = key;
    }
    else if (key == "space origin")
    {
      const auto v = numbers(value, file, "space origin");
      if (v.size() != 3)
        throw SceneError(file.string() + ": 'space origin' must have 3 numbers");
      n.origin = {v[0], v[1], v[2]};
      spaceField = key;
    }
    else if (key == "spacings")
    {
      n.spacings = numbers(value, file, "spacings");
    }
    else if (key == "data file" || key == "datafile")
    {
      throw SceneError(file.string() +
                       " is a detached-header NRRD; CAPS reads attached data only: re-save it as a single .nrrd file");
    }
    else if (key == "line skip" || key == "lineskip" || key == "byte skip" || key == "byteskip")
    {
      if (value != "0")
        throw SceneError(file.string() + ": NRRD '" + key + "' is not supported");
    }
  }
  if (!ended)
    throw SceneError(file.string() + " is truncated (the NRRD header does not end)");
  if (!n.vtkType || n.dimension < 1 || n.sizes.size() != static_cast<std::size_t>(n.dimension))
    throw SceneError(file.string() + ": NRRD header lacks a valid type, dimension or sizes");
  for (std::size_t s : n.sizes)
    if (s < 1)
      throw SceneError(file.string() + ": NRRD sizes must be 1 or more");

  // Bring the geometry to LPS, the patient frame of CAPS.
  if (space.empty() && !spaceField.empty())
    throw SceneError(file.string() + " gives '" + spaceField +
                     "' but no 'space', so its patient frame is unknown: "
                     "re-save it with space LPS or RAS (3D Slicer does)");
  if (!space.empty())
  {
    n.hasSpace = true;
    std::array<double, 3> flip{1, 1, 1};
    if (space == "right-anterior-superior" || space == "RAS")
      flip = {-1, -1, 1};
    else if (space == "left-anterior-superior" || space == "LAS")
      flip = {1, -1, 1};
    else if (space != "left-posterior-superior" && space != "LPS")
      throw SceneError(file.string() + ": NRRD space '" + space + "' is not supported; convert it to LPS or RAS");
    const std::size_t axes = static_cast<std::size_t>(std::min(n.dimension, 3));
    if (dirs.empty() && n.dimension >= 2)
      throw SceneError(file.string() + ": NRRD has a space but no 'space directions'");
    if (!dirs.empty() && dirs.size() != static_cast<std::size_t>(n.dimension) * 3)
      throw SceneError(file.string() + ": 'space directions' must give " + std::to_string(n.dimension) +
                       " vectors of 3 numbers");
    for (std::size_t a = 0; a < axes && !dirs.empty(); ++a)
      for (std::size_t c = 0; c < 3; ++c)
        n.dirs[a][c] = dirs[a * 3 + c];
    for (std::size_t c = 0; c < 3; ++c)
    {
      n.origin[c] *= flip[c];
      for (std::size_t a = 0; a < 3; ++a)
        n.dirs[a][c] *= flip[c];
    }
  }

  if (encoding == "gzip" || encoding == "gz")
    n.gzip = true;
  else if (encoding != "raw")
    throw SceneError(file.string() + ": NRRD encoding '" + encoding + "' is not supported; use raw or gzip");
  n.bigEndian = endian == "big";

  // Sizes come from the file: check the product and that the data can be there.
  const std::size_t maxBytes = std::numeric_limits<std::size_t>::max();
  n.bytes = static_cast<std::size_t>(sizeOfVtkType(n.vtkType));
  for (std::size_t s : n.sizes)
  {
    if (s > maxBytes / n.bytes)
      throw SceneError(file.string() + ": NRRD sizes are too large (damaged header?)");
    n.bytes *= s;
  }
  const std::streamoff start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  in.seekg(start);
  if (start < 0 || end < start)
    throw SceneError("cannot read " + file.string() + ": the file could not be measured");
  const auto payload = static_cast<std::size_t>(end - start);
  if (!n.gzip && n.bytes > payload)
    throw SceneError(file.string() + " is truncated (" + std::to_string(payload) + " of " + std::to_string(n.bytes) +
                     " bytes of image data): restore it from a backup or re-save the scene");
  constexpr std::size_t kMaxGzipRatio = 1032; // deflate never compresses better than this
  if (n.gzip && payload <= maxBytes / kMaxGzipRatio && n.bytes > payload * kMaxGzipRatio)
    throw SceneError(file.string() + " is truncated or damaged: its header asks for " + std::to_string(n.bytes) +
                     " bytes of image data, more than its " + std::to_string(payload) +
                     " bytes of gzip data can hold; restore it from a backup or re-save the scene");
  return n;
}

// Reads the image data at the current position of @a in into dst[0, n.bytes), little endian.
void readData(std::ifstream& in, const Nrrd& n, char* dst, const path& file)
{
  if (n.gzip)
  {
    inflateInto(in, dst, n.bytes, file);
  }
  else
  {
    in.read(dst, static_cast<std::streamsize>(n.bytes));
    if (static_cast<std::size_t>(in.gcount()) != n.bytes)
      throw SceneError(file.string() + " is truncated (" + std::to_string(in.gcount()) + " of " +
                       std::to_string(n.bytes) +
                       " bytes of image data): restore it from a backup or re-save the scene");
  }
  const auto elem = static_cast<std::size_t>(sizeOfVtkType(n.vtkType));
  if (n.bigEndian && elem > 1)
    for (std::size_t i = 0; i < n.bytes; i += elem)
      std::reverse(dst + i, dst + i + elem);
}

// Non-SceneError failures (out of memory, stream errors) still name the file.
template <class F> auto withFileErrors(const path& file, F read)
{
  try
  {
    return read();
  }
  catch (const SceneError&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    throw SceneError("cannot read " + file.string() + " (" + e.what() + "); it is not a file CAPS can read");
  }
}

} // namespace

void NrrdIO::writeImage(vtkImageData* image, const path& file, Encoding encoding)
{
  if (!image || !image->GetPointData()->GetScalars())
    throw SceneError("cannot write " + file.string() + ": the image is empty");
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (scalars->GetNumberOfComponents() != 1)
    throw SceneError("cannot write " + file.string() + ": NRRD writing supports single-component images only");
  const auto& names = typeNames();
  auto it =
    std::find_if(names.begin(), names.end(), [&](const TypeName& t) { return t.vtkType == image->GetScalarType(); });
  if (it == names.end())
    throw SceneError("cannot write " + file.string() + ": scalar type " + image->GetScalarTypeAsString() +
                     " is not supported");

  int dims[3];
  image->GetDimensions(dims);
  double spacing[3], origin[3];
  image->GetSpacing(spacing);
  // The first voxel's position: handles extents that do not start at 0.
  const int* ext = image->GetExtent();
  image->TransformIndexToPhysicalPoint(ext[0], ext[2], ext[4], origin);
  vtkMatrix3x3* d = image->GetDirectionMatrix();
  double cols[3][3];
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      cols[a][c] = d->GetElement(c, a) * spacing[a];

  std::string h =
    "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n";
  h += std::string("type: ") + it->canonical + "\n";
  h += "dimension: 3\n";
  h += "space: left-posterior-superior\n";
  h += "sizes: " + std::to_string(dims[0]) + " " + std::to_string(dims[1]) + " " + std::to_string(dims[2]) + "\n";
  h += "space directions: " + vec3(cols[0]) + " " + vec3(cols[1]) + " " + vec3(cols[2]) + "\n";
  h += "kinds: domain domain domain\n";
  h += "endian: little\n";
  h += std::string("encoding: ") + (encoding == Encoding::Gzip ? "gzip" : "raw") + "\n";
  h += "space origin: " + vec3(origin) + "\n\n";
  const std::size_t bytes =
    static_cast<std::size_t>(scalars->GetNumberOfTuples()) * static_cast<std::size_t>(scalars->GetDataTypeSize());
  writeNrrd(file, h, scalars->GetVoidPointer(0), bytes, encoding);
}

vtkSmartPointer<vtkImageData> NrrdIO::readImage(const path& file)
{
  return withFileErrors(file, [&] {
    std::ifstream in(file, std::ios::binary);
    const Nrrd n = readHeader(in, file);
    if (n.dimension != 2 && n.dimension != 3)
      throw SceneError(file.string() + " holds a " + std::to_string(n.dimension) +
                       "D NRRD; a 2D or 3D scalar image was expected");
    for (std::size_t s : n.sizes)
      if (s > static_cast<std::size_t>(INT_MAX))
        throw SceneError(file.string() + ": image size " + std::to_string(s) +
                         " is more than CAPS can hold on one axis");
    auto image = vtkSmartPointer<vtkImageData>::New();
    const int nz = n.dimension == 3 ? static_cast<int>(n.sizes[2]) : 1;
    image->SetDimensions(static_cast<int>(n.sizes[0]), static_cast<int>(n.sizes[1]), nz);
    double spacing[3] = {1, 1, 1};
    double dir[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    if (n.hasSpace)
    {
      for (int a = 0; a < n.dimension; ++a)
      {
        const auto& d = n.dirs[static_cast<std::size_t>(a)];
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(len > 0) || !std::isfinite(len))
          throw SceneError(file.string() + ": 'space directions' has a zero or invalid vector");
        spacing[a] = len;
        for (int c = 0; c < 3; ++c)
          dir[c * 3 + a] = d[static_cast<std::size_t>(c)] / len; // row c, column a
      }
      if (n.dimension == 2)
      { // the third column: normal to the plane of the first two
        const double x = dir[3] * dir[7] - dir[6] * dir[4], y = dir[6] * dir[1] - dir[0] * dir[7],
                     z = dir[0] * dir[4] - dir[3] * dir[1];
        const double len = std::sqrt(x * x + y * y + z * z);
        if (!(len > 0))
          throw SceneError(file.string() + ": 'space directions' gives two parallel vectors");
        dir[2] = x / len;
        dir[5] = y / len;
        dir[8] = z / len;
      }
    }
    else
    {
      for (std::size_t a = 0; a < n.spacings.size() && a < 3; ++a)
        if (n.spacings[a] > 0)
          spacing[a] = n.spacings[a];
    }
    image->SetSpacing(spacing);
    image->SetOrigin(n.origin.data());
    image->SetDirectionMatrix(dir);
    image->AllocateScalars(n.vtkType, 1);
    const auto elem = static_cast<std::size_t>(sizeOfVtkType(n.vtkType));
    if (!image->GetScalarPointer() || static_cast<std::size_t>(image->GetNumberOfPoints()) * elem != n.bytes)
      throw SceneError("cannot read " + file.string() + ": not enough memory for its " + std::to_string(n.bytes) +
                       " bytes of image data");
    readData(in, n, static_cast<char*>(image->GetScalarPointer()), file);
    return image;
  });
}

void NrrdIO::writeMatrix(const Eigen::MatrixXf& values, const path& file, Encoding encoding)
{
  std::string h = "NRRD0004\n";
  h += "type: float\n";
  h += "dimension: 2\n";
  h += "sizes: " + std::to_string(values.rows()) + " " + std::to_string(values.cols()) + "\n";
  h += "kinds: domain domain\n";
  h += "endian: little\n";
  h += std::string("encoding: ") + (encoding == Encoding::Gzip ? "gzip" : "raw") + "\n\n";
  writeNrrd(file, h, values.data(), static_cast<std::size_t>(values.size()) * sizeof(float), encoding);
}

Eigen::MatrixXf NrrdIO::readMatrix(const path& file)
{
  return withFileErrors(file, [&] {
    std::ifstream in(file, std::ios::binary);
    const Nrrd n = readHeader(in, file);
    if (n.dimension != 2 || n.vtkType != VTK_FLOAT)
      throw SceneError(file.string() +
                       " is not a 2D float NRRD as a range map must be: re-save the scene or restore a backup");
    // The sizes are at most the file size (checked by readHeader), so they fit an Eigen::Index.
    Eigen::MatrixXf m(static_cast<Eigen::Index>(n.sizes[0]), static_cast<Eigen::Index>(n.sizes[1]));
    readData(in, n, reinterpret_cast<char*>(m.data()), file);
    return m;
  });
}

} // namespace caps
