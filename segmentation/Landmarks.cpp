#include "segmentation/Landmarks.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace caps::seg {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr const char* kShortHeader = "name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm";
constexpr const char* kHeader =
  "name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm,ct_skin_normal_mm,ct_nearest_bone_mm,depth_mm,convention,note";
constexpr std::size_t kShortColumns = 8, kColumns = 13;

void checkFrame(const RangeMap& reference, const RangeMap& map, const char* what)
{
  if (!map.empty() && !reference.empty() && map.frame() != reference.frame())
    throw std::invalid_argument(std::string("The ") + what + " map is on another cylinder or grid than the skin map.");
}

double sampleOrNaN(const RangeMap& map, double theta, double z)
{
  return map.empty() ? RangeMap::quietNaN() : map.sample(theta, z);
}

std::string number(double value)
{
  if (!std::isfinite(value))
    return {};
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::vector<std::string> splitFields(const std::string& line)
{
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ','))
    fields.push_back(field);
  if (!line.empty() && line.back() == ',')
    fields.emplace_back();
  return fields;
}

std::string trim(const std::string& s)
{
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos)
    return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

} // namespace

const std::vector<LandmarkDefinition>& standardLandmarks()
{
  static const std::vector<LandmarkDefinition> definitions = {
    {"supraglabella", "Deepest point of the concavity of the forehead above the glabella, on the midline."},
    {"glabella", "Most prominent point of the forehead between the eyebrows, on the midline."},
    {"nasion", "Deepest point of the soft-tissue profile between the forehead and the nose."},
    {"mid_nasal", "On the nasal dorsum half-way from the nasion to the rhinion, on the midline."},
    {"rhinion", "Skin over the lower end of the nasal bones (the bony rhinion), on the midline."},
    {"pronasale", "Nose tip: the most anterior point of the nose."},
    {"subnasale", "Where the columella of the nose meets the upper lip, on the midline."},
    {"mid_philtrum", "Middle of the philtrum, half-way from the subnasale to the upper lip."},
    {"labrale_superius", "Most anterior point of the upper lip on the midline."},
    {"labrale_inferius", "Most anterior point of the lower lip on the midline."},
    {"sublabiale", "Deepest point of the fold between the lower lip and the chin (the tables' chin-lip fold)."},
    {"pogonion", "Chin: the most anterior point of the soft-tissue chin."},
    {"menton", "Lowest point of the soft-tissue chin on the midline."},
    {"zygion_left", "Most lateral point of the skin over the left zygomatic arch."},
    {"zygion_right", "Most lateral point of the skin over the right zygomatic arch."},
    {"gonion_left", "Skin over the angle of the left mandible."},
    {"gonion_right", "Skin over the angle of the right mandible."},
    {"mid_cheek_left",
     "Left cheek over the maxilla under the pupil (32 mm from the midline), at the nose tip's height."},
    {"mid_cheek_right",
     "Right cheek over the maxilla under the pupil (32 mm from the midline), at the nose tip's height."},
    {"supraorbital_left", "Skin over the upper rim of the left orbit above the pupil (the tables' mid-supraorbital)."},
    {"supraorbital_right",
     "Skin over the upper rim of the right orbit above the pupil (the tables' mid-supraorbital)."},
    {"infraorbital_left", "Skin over the lower rim of the left orbit below the pupil (the tables' mid-infraorbital)."},
    {"infraorbital_right",
     "Skin over the lower rim of the right orbit below the pupil (the tables' mid-infraorbital)."},
    {"forehead", "Mid-forehead on the midline, 75 mm above the nose tip (below the hairline)."},
  };
  return definitions;
}

std::string landmarkDescription(std::string_view name)
{
  for (const auto& d : standardLandmarks())
    if (name == d.name)
      return d.description;
  return {};
}

std::vector<LandmarkThickness> landmarkThickness(const std::vector<Landmark>& landmarks, const RangeMap& skin,
                                                 const RangeMap& radial, const RangeMap& normal)
{
  checkFrame(skin, radial, "radial thickness");
  checkFrame(skin, normal, "normal thickness");
  checkFrame(radial, normal, "normal thickness");
  std::vector<LandmarkThickness> rows;
  rows.reserve(landmarks.size());
  for (const Landmark& l : landmarks)
  {
    LandmarkThickness row;
    row.landmark = l;
    const double r = sampleOrNaN(skin, l.theta, l.z);
    if (std::isfinite(r))
      row.position = skin.frame().toWorld(r, l.theta, l.z);
    row.radial = sampleOrNaN(radial, l.theta, l.z);
    row.normal = sampleOrNaN(normal, l.theta, l.z);
    rows.push_back(row);
  }
  return rows;
}

void writeLandmarkCsv(const std::filesystem::path& path, const std::vector<LandmarkThickness>& rows)
{
  std::ostringstream out;
  out << kHeader << '\n';
  for (const auto& row : rows)
  {
    const std::string& name = row.landmark.name;
    if (name.empty() || name.find_first_of(",\"\r\n") != std::string::npos)
      throw std::invalid_argument("The landmark name \"" + name +
                                  "\" cannot be written to CSV: it must be non-empty and hold no "
                                  "comma, quote or line break.");
    for (const std::string* text : {&row.convention, &row.note})
      if (text->find_first_of(",\"\r\n") != std::string::npos)
        throw std::invalid_argument("\"" + *text +
                                    "\" cannot be written to the landmark CSV: it must hold no comma, quote or line "
                                    "break.");
    out << name << ',' << number(row.landmark.theta / kDegree) << ',' << number(row.landmark.z) << ','
        << number(row.position.x()) << ',' << number(row.position.y()) << ',' << number(row.position.z()) << ','
        << number(row.radial) << ',' << number(row.normal) << ',' << number(row.ctSkinNormal) << ','
        << number(row.ctNearestBone) << ',' << number(row.depth) << ',' << row.convention << ',' << row.note << '\n';
  }
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file)
      throw std::runtime_error("Cannot write the landmark table " + temporary.string() + ".");
    file << out.str();
    file.close();
    if (!file)
      throw std::runtime_error("Writing the landmark table " + temporary.string() + " failed.");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error)
  {
    std::filesystem::remove(temporary, error);
    throw std::runtime_error("Cannot replace the landmark table " + path.string() + ".");
  }
}

std::vector<LandmarkThickness> readLandmarkCsv(const std::filesystem::path& path)
{
  std::ifstream file(path, std::ios::binary);
  if (!file)
    throw std::runtime_error("Cannot open the landmark table " + path.string() + ".");
  auto fail = [&path](int line, const std::string& what) {
    return std::runtime_error(path.string() + ", line " + std::to_string(line) + ": " + what);
  };
  std::string line;
  int lineNumber = 0;
  bool header = false;
  std::size_t columns = kColumns;
  std::vector<LandmarkThickness> rows;
  while (std::getline(file, line))
  {
    ++lineNumber;
    if (trim(line).empty())
      continue;
    auto fields = splitFields(line);
    for (auto& f : fields)
      f = trim(f);
    if (!header)
    {
      std::string joined;
      for (std::size_t i = 0; i < fields.size(); ++i)
        joined += (i ? "," : "") + fields[i];
      if (joined != kHeader && joined != kShortHeader)
        throw fail(lineNumber, std::string("the header must be \"") + kHeader + "\" (or its first 8 columns).");
      columns = joined == kHeader ? kColumns : kShortColumns;
      header = true;
      continue;
    }
    if (fields.size() != columns)
      throw fail(lineNumber,
                 "expected " + std::to_string(columns) + " fields, found " + std::to_string(fields.size()) + ".");
    double v[10];
    const int numberFields =
      int(columns) - (columns == kColumns ? 3 : 1); // all but the name (the convention, the note)
    for (int k = 0; k < 10; ++k)
      v[k] = RangeMap::quietNaN();
    for (int k = 0; k < numberFields; ++k)
    {
      const std::string& f = fields[k + 1];
      if (f.empty() || f == "nan" || f == "NaN")
      {
        v[k] = RangeMap::quietNaN();
        continue;
      }
      const auto result = std::from_chars(f.data(), f.data() + f.size(), v[k]);
      if (result.ec != std::errc() || result.ptr != f.data() + f.size())
        throw fail(lineNumber, "\"" + f + "\" is not a number.");
    }
    if (fields[0].empty() || !std::isfinite(v[0]) || !std::isfinite(v[1]))
      throw fail(lineNumber, "name, theta_deg and z_mm are required.");
    LandmarkThickness row;
    row.landmark = {fields[0], v[0] * kDegree, v[1]};
    row.position = Eigen::Vector3d(v[2], v[3], v[4]);
    row.radial = v[5];
    row.normal = v[6];
    row.ctSkinNormal = v[7];
    row.ctNearestBone = v[8];
    row.depth = v[9];
    if (columns == kColumns)
    {
      row.convention = fields[11];
      row.note = fields[12];
    }
    rows.push_back(row);
  }
  if (!header)
    throw fail(lineNumber, "the file is empty (no header).");
  return rows;
}

} // namespace caps::seg
