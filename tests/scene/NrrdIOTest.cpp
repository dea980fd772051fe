// NRRD files checked independently of our reader: header text, VTK's
// vtkNrrdReader on a raw file, zlib on the gzip payload; and error handling.

#include <gtest/gtest.h>
#include <vtkNrrdReader.h>
#include <zlib.h>

#include <fstream>
#include <iterator>

#include "SceneTestUtils.h"
#include "scene/NrrdIO.h"
#include "scene/SceneError.h"

namespace caps {
namespace {

using test::TempDir;

std::string slurp(const std::filesystem::path& p)
{
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string headerOf(const std::string& bytes)
{
  return bytes.substr(0, bytes.find("\n\n") + 2);
}

TEST(NrrdIO, HeaderIsWhatSlicerExpects)
{
  TempDir tmp;
  auto image = test::makeImage(VTK_SHORT);
  NrrdIO::writeImage(image, tmp.path() / "v.nrrd");
  const std::string h = headerOf(slurp(tmp.path() / "v.nrrd"));
  EXPECT_EQ(h.rfind("NRRD0004\n", 0), 0u);
  EXPECT_NE(h.find("type: short\n"), std::string::npos);
  EXPECT_NE(h.find("dimension: 3\n"), std::string::npos);
  EXPECT_NE(h.find("space: left-posterior-superior\n"), std::string::npos);
  EXPECT_NE(h.find("sizes: 5 4 3\n"), std::string::npos);
  EXPECT_NE(h.find("kinds: domain domain domain\n"), std::string::npos);
  EXPECT_NE(h.find("endian: little\n"), std::string::npos);
  EXPECT_NE(h.find("encoding: gzip\n"), std::string::npos);
  EXPECT_NE(h.find("space origin: (-12.5,30.25,-100)\n"), std::string::npos);
  // Columns of direction x spacing: the first axis is rotated 30 degrees about z.
  EXPECT_NE(h.find("space directions: (0.43301270189221"), std::string::npos) << h;
  EXPECT_NE(h.find(",0) (-0.37"), std::string::npos) << h;
  EXPECT_NE(h.find(") (0,0,2.5)\n"), std::string::npos) << h;
}

TEST(NrrdIO, GzipPayloadDecompressesWithZlibToTheVoxels)
{
  TempDir tmp;
  auto image = test::makeImage(VTK_FLOAT, 17, 9, 5);
  NrrdIO::writeImage(image, tmp.path() / "v.nrrd");
  const std::string bytes = slurp(tmp.path() / "v.nrrd");
  const std::size_t start = headerOf(bytes).size();
  std::vector<float> out(17 * 9 * 5);
  z_stream zs{};
  ASSERT_EQ(inflateInit2(&zs, 15 + 16), Z_OK); // gzip wrapper only
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + start));
  zs.avail_in = static_cast<uInt>(bytes.size() - start);
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size() * sizeof(float));
  EXPECT_EQ(inflate(&zs, Z_FINISH), Z_STREAM_END);
  EXPECT_EQ(zs.avail_out, 0u);
  inflateEnd(&zs);
  EXPECT_EQ(0, std::memcmp(out.data(), image->GetScalarPointer(), out.size() * sizeof(float)));
}

TEST(NrrdIO, RawFileReadsInVtkNrrdReader)
{
  TempDir tmp;
  // vtkNrrdReader takes a first axis of 9 samples or fewer for vector
  // components, and ignores rotation: give it 12 samples and no rotation.
  auto image = test::makeImage(VTK_UNSIGNED_SHORT, 12, 5, 4);
  const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  image->SetDirectionMatrix(identity);
  NrrdIO::writeImage(image, tmp.path() / "raw.nrrd", NrrdIO::Encoding::Raw);
  auto reader = vtkSmartPointer<vtkNrrdReader>::New();
  ASSERT_TRUE(reader->CanReadFile((tmp.path() / "raw.nrrd").c_str()));
  reader->SetFileName((tmp.path() / "raw.nrrd").c_str());
  reader->Update();
  vtkImageData* out = reader->GetOutput();
  int dims[3];
  out->GetDimensions(dims);
  EXPECT_EQ(dims[0], 12);
  EXPECT_EQ(dims[1], 5);
  EXPECT_EQ(dims[2], 4);
  EXPECT_EQ(out->GetScalarType(), VTK_UNSIGNED_SHORT);
  EXPECT_EQ(out->GetNumberOfScalarComponents(), 1);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_NEAR(out->GetSpacing()[i], image->GetSpacing()[i], 1e-9);
    EXPECT_NEAR(out->GetOrigin()[i], image->GetOrigin()[i], 1e-9);
  }
  EXPECT_EQ(0, std::memcmp(out->GetScalarPointer(), image->GetScalarPointer(), 12 * 5 * 4 * sizeof(unsigned short)));
  // And our reader agrees with the raw file too.
  test::expectSameImage(image, NrrdIO::readImage(tmp.path() / "raw.nrrd"));
}

TEST(NrrdIO, ReadsRasBigEndianRawFromOtherTools)
{
  TempDir tmp;
  std::ofstream f(tmp.path() / "ras.nrrd", std::ios::binary);
  f << "NRRD0005\n# from another tool\ntype: int16\ndimension: 3\nspace: right-anterior-superior\n"
       "sizes: 2 1 1\nspace directions: (-1,0,0) (0,-2,0) (0,0,3)\nkinds: domain domain domain\n"
       "endian: big\nencoding: raw\nspace origin: (10,20,30)\nkey:=value\n\n";
  const unsigned char data[4] = {0x01, 0x02, 0xFF, 0xFE}; // 258, -2
  f.write(reinterpret_cast<const char*>(data), 4);
  f.close();
  auto image = NrrdIO::readImage(tmp.path() / "ras.nrrd");
  EXPECT_EQ(image->GetScalarType(), VTK_SHORT);
  EXPECT_EQ(*static_cast<short*>(image->GetScalarPointer(0, 0, 0)), 258);
  EXPECT_EQ(*static_cast<short*>(image->GetScalarPointer(1, 0, 0)), -2);
  EXPECT_DOUBLE_EQ(image->GetOrigin()[0], -10); // RAS -> LPS flips x and y
  EXPECT_DOUBLE_EQ(image->GetOrigin()[1], -20);
  EXPECT_DOUBLE_EQ(image->GetOrigin()[2], 30);
  EXPECT_DOUBLE_EQ(image->GetSpacing()[1], 2);
  EXPECT_DOUBLE_EQ(image->GetDirectionMatrix()->GetElement(0, 0), 1); // -1 in RAS is +1 in LPS
  EXPECT_DOUBLE_EQ(image->GetDirectionMatrix()->GetElement(1, 1), 1);
}

TEST(NrrdIO, MatrixKeepsNaNAndThetaFastest)
{
  TempDir tmp;
  Eigen::MatrixXf m(3, 2);
  m << 1, 4, 2, std::numeric_limits<float>::quiet_NaN(), 3, 6;
  NrrdIO::writeMatrix(m, tmp.path() / "m.nrrd", NrrdIO::Encoding::Raw);
  const std::string bytes = slurp(tmp.path() / "m.nrrd");
  EXPECT_NE(bytes.find("sizes: 3 2\n"), std::string::npos);
  const float* raw = reinterpret_cast<const float*>(bytes.data() + headerOf(bytes).size());
  EXPECT_EQ(raw[1], 2.0f); // second θ sample at the first z
  EXPECT_EQ(raw[3], 4.0f);
  Eigen::MatrixXf back = NrrdIO::readMatrix(tmp.path() / "m.nrrd");
  EXPECT_TRUE(std::isnan(back(1, 1)));
  EXPECT_EQ(back(2, 1), 6.0f);
}

TEST(NrrdIO, TruncatedOrForeignFilesThrowNamingTheFile)
{
  TempDir tmp;
  const auto good = tmp.path() / "good.nrrd";
  NrrdIO::writeImage(test::makeImage(VTK_FLOAT, 30, 30, 30), good);
  const std::string bytes = slurp(good);
  auto expectError = [&](const std::filesystem::path& p, const std::string& what) {
    try
    {
      NrrdIO::readImage(p);
      ADD_FAILURE() << "no error for " << p;
    }
    catch (const SceneError& e)
    {
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  std::ofstream(tmp.path() / "cut.nrrd", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  expectError(tmp.path() / "cut.nrrd", "truncated");
  std::ofstream(tmp.path() / "head.nrrd", std::ios::binary) << bytes.substr(0, 40);
  expectError(tmp.path() / "head.nrrd", "truncated");
  std::ofstream(tmp.path() / "foreign.nrrd", std::ios::binary) << "P6\n2 2\n255\n0123456789ab";
  expectError(tmp.path() / "foreign.nrrd", "not a NRRD");
  std::ofstream(tmp.path() / "weird.nrrd", std::ios::binary) << "NRRD0004\ntype: quaternion\n\n";
  expectError(tmp.path() / "weird.nrrd", "not supported");
  expectError(tmp.path() / "absent.nrrd", "missing");

  auto raw = tmp.path() / "raw.nrrd";
  NrrdIO::writeImage(test::makeImage(VTK_INT), raw, NrrdIO::Encoding::Raw);
  const std::string rawBytes = slurp(raw);
  std::ofstream(raw, std::ios::binary | std::ios::trunc) << rawBytes.substr(0, rawBytes.size() - 3);
  expectError(raw, "truncated");
}

// Writes @a header followed by @a payloadBytes zero bytes (sparse on disk, so
// a file of gigabytes costs nothing).
void writeHeaderAndZeros(const std::filesystem::path& p, const std::string& header, std::uintmax_t payloadBytes)
{
  {
    std::ofstream(p, std::ios::binary) << header;
  }
  std::filesystem::resize_file(p, header.size() + payloadBytes);
}

void expectReadError(const std::filesystem::path& p, const std::string& what)
{
  try
  {
    NrrdIO::readImage(p);
    ADD_FAILURE() << "no error for " << p;
  }
  catch (const SceneError& e)
  {
    EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

// A size above INT_MAX used to be cast to int for vtkImageData and the whole
// payload then copied into the smaller image: a heap overflow.
TEST(NrrdIO, SizesAboveIntMaxAreRejected)
{
  TempDir tmp;
  const auto p = tmp.path() / "wide.nrrd";
  writeHeaderAndZeros(p, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2147483648 1 1\nencoding: raw\n\n", 2147483648u);
  expectReadError(p, "more than CAPS can hold");
}

// Sizes come from the file: they must be whole numbers >= 1 whose product
// does not overflow, and the file must be able to hold that much data before
// anything is allocated (a 200-byte header must not claim terabytes).
TEST(NrrdIO, HeaderSizesAreCheckedBeforeAllocating)
{
  TempDir tmp;
  const std::string head = "NRRD0004\ntype: float\ndimension: 3\nencoding: raw\n";
  int i = 0;
  for (const char* sizes : {"-1 2 2", "nan 2 2", "1e30 2 2", "2.5 2 2", "0 2 2", "2 2"})
  {
    const auto p = tmp.path() / ("bad" + std::to_string(i++) + ".nrrd");
    writeHeaderAndZeros(p, head + "sizes: " + sizes + "\n\n", 64);
    expectReadError(p, "NRRD");
  }
  // 2^32 * 2^32 * 4 bytes wraps to 0 in 64 bits.
  writeHeaderAndZeros(tmp.path() / "wrap.nrrd", head + "sizes: 4294967296 4294967296 1\n\n", 64);
  expectReadError(tmp.path() / "wrap.nrrd", "too large");
  // 2^50 bytes asked, 100 given.
  writeHeaderAndZeros(tmp.path() / "huge.nrrd", head + "sizes: 65536 65536 65536\n\n", 100);
  expectReadError(tmp.path() / "huge.nrrd", "truncated");
  const std::string gzHead = "NRRD0004\ntype: float\ndimension: 3\nencoding: gzip\nsizes: 65536 65536 65536\n\n";
  writeHeaderAndZeros(tmp.path() / "huge-gz.nrrd", gzHead, 100);
  expectReadError(tmp.path() / "huge-gz.nrrd", "truncated or damaged");
  EXPECT_THROW(NrrdIO::readMatrix(tmp.path() / "huge-gz.nrrd"), SceneError);
}

// "space dimension" and "space directions" without "space": the frame is
// unknown, so do not silently load at 1 mm identity.
TEST(NrrdIO, SpaceDirectionsWithoutSpaceAreRejected)
{
  TempDir tmp;
  const auto p = tmp.path() / "nospace.nrrd";
  writeHeaderAndZeros(p,
                      "NRRD0004\ntype: uchar\ndimension: 3\nspace dimension: 3\nsizes: 2 1 1\n"
                      "space directions: (2,0,0) (0,2,0) (0,0,2)\nencoding: raw\n\n",
                      2);
  expectReadError(p, "no 'space'");
}

TEST(NrrdIO, Reads2DImageWithSpaceAndTwoDirections)
{
  TempDir tmp;
  const auto p = tmp.path() / "slice.nrrd";
  {
    std::ofstream f(p, std::ios::binary);
    f << "NRRD0004\ntype: uchar\ndimension: 2\nspace: left-posterior-superior\nsizes: 3 2\n"
         "space directions: (0,2,0) (-3,0,0)\nspace origin: (1,2,3)\nencoding: raw\n\n";
    f << std::string("\x01\x02\x03\x04\x05\x06", 6);
  }
  auto image = NrrdIO::readImage(p);
  int dims[3];
  image->GetDimensions(dims);
  EXPECT_EQ(dims[0], 3);
  EXPECT_EQ(dims[1], 2);
  EXPECT_EQ(dims[2], 1);
  EXPECT_DOUBLE_EQ(image->GetSpacing()[0], 2);
  EXPECT_DOUBLE_EQ(image->GetSpacing()[1], 3);
  EXPECT_DOUBLE_EQ(image->GetOrigin()[2], 3);
  const double expected[3][3] = {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}; // rows; the third column is the normal
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_DOUBLE_EQ(image->GetDirectionMatrix()->GetElement(r, c), expected[r][c]);
  EXPECT_EQ(*static_cast<unsigned char*>(image->GetScalarPointer(2, 1, 0)), 6);
}

} // namespace
} // namespace caps
