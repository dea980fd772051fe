// The structural DICOM check: every sample file is sound, every cut of a
// file is damaged, and reading never reaches GDCM's aborting assertions.

#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "segmentation/CtReader.h"
#include "segmentation/DicomFileCheck.h"
#include "TestPaths.h"

namespace fs = std::filesystem;
using caps::seg::checkDicomFile;
using caps::seg::DicomFileKind;

namespace {

std::vector<char> bytesOf(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& file, const std::vector<char>& bytes, size_t count)
{
  std::ofstream(file, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(count));
}

} // namespace

TEST(DicomFileCheck, EverySampleSliceIsSound)
{
  int files = 0;
  for (const auto& entry : fs::directory_iterator(caps::test::sampleCt()))
  {
    const auto check = checkDicomFile(entry.path());
    EXPECT_EQ(check.kind, DicomFileKind::Sound) << entry.path() << ": " << check.problem;
    ++files;
  }
  EXPECT_EQ(files, 295);
}

// Cut a slice at many places, from inside the meta header to the last
// fragment of the JPEG 2000 pixel data: each cut is reported as damaged
// and the reader answers with an error instead of aborting.
TEST(DicomFileCheck, EveryCutIsDamagedAndReadsFailCleanly)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path source = *fs::directory_iterator(caps::test::sampleCt());
  const auto bytes = bytesOf(source);
  const fs::path cut = folder / "cut.dcm";
  int cuts = 0;
  for (size_t size = 132; size < bytes.size(); size += size < 4000 ? 7 : 997)
  {
    writeBytes(cut, bytes, size);
    const auto check = checkDicomFile(cut);
    ASSERT_EQ(check.kind, DicomFileKind::Damaged) << "cut at " << size;
    EXPECT_FALSE(check.problem.empty());
    EXPECT_THROW(caps::seg::readCtVolume(cut), caps::seg::CtReadError) << "cut at " << size;
    ++cuts;
  }
  EXPECT_GT(cuts, 500);
}

TEST(DicomFileCheck, TextAndShortFilesAreNotDicom)
{
  const fs::path folder = caps::test::scratchFolder();
  std::ofstream(folder / "notes.txt") << "not an image at all, but long enough to have 132 bytes "
                                         "of text in it so the DICM check looks at the right "
                                         "place and finds nothing there.\n";
  EXPECT_EQ(checkDicomFile(folder / "notes.txt").kind, DicomFileKind::NotDicom);
  std::ofstream(folder / "tiny.dcm") << "DICM";
  EXPECT_EQ(checkDicomFile(folder / "tiny.dcm").kind, DicomFileKind::NotDicom);
}

TEST(DicomFileCheck, CorruptLengthIsDamaged)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path source = *fs::directory_iterator(caps::test::sampleCt());
  auto bytes = bytesOf(source);
  // The first element after the meta group length: make its length huge.
  // (0002,0001) OB: tag 4 + VR 2 + reserved 2 + length 4 at offset 144.
  ASSERT_EQ(bytes[144], 0x02);
  ASSERT_EQ(bytes[146], 0x01);
  bytes[152] = bytes[153] = bytes[154] = 0x7F;
  writeBytes(folder / "corrupt.dcm", bytes, bytes.size());
  const auto check = checkDicomFile(folder / "corrupt.dcm");
  EXPECT_EQ(check.kind, DicomFileKind::Damaged);
  EXPECT_NE(check.problem.find("(0002,0001)"), std::string::npos) << check.problem;
}
