#include "planning/MuscleSet.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "planning/SkinTensionLines.h"

namespace fs = std::filesystem;

namespace caps::expression {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// Adult mean nasion–subnasale height (Farkas 1994), as planning::FaceLayout.
constexpr double kMeanNasionSubnasale = 53.0;

std::string trim(const std::string& s)
{
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos)
    return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::string joined(const std::vector<std::string>& names)
{
  std::string out;
  for (const auto& n : names)
  {
    if (!out.empty())
      out += ", ";
    out += n;
  }
  return out;
}

bool endsWith(const std::string& s, const std::string& tail)
{
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// _left ↔ _right; other names unchanged.
std::string mirroredName(const std::string& name)
{
  if (endsWith(name, "_left"))
    return name.substr(0, name.size() - 5) + "_right";
  if (endsWith(name, "_right"))
    return name.substr(0, name.size() - 6) + "_left";
  return name;
}

bool isDerived(const std::string& name)
{
  const auto d = derivedAnchorNames();
  return std::find(d.begin(), d.end(), name) != d.end();
}

const seg::Landmark* findLandmark(const std::vector<seg::Landmark>& landmarks, const std::string& name)
{
  for (const auto& l : landmarks)
    if (l.name == name && std::isfinite(l.z) && std::isfinite(l.theta))
      return &l;
  return nullptr;
}

/// The parser's state: where keys go.
class Parser
{
public:
  Parser(fs::path file) : file_(std::move(file)) {}

  MuscleSet run();

private:
  [[noreturn]] void fail(const std::string& message, int line = -1) const
  {
    throw MuscleSetFileError(file_, line < 0 ? line_ : line, message);
  }
  double number(const std::string& text, const std::string& what) const;
  AttachmentDefinition point(const std::string& value, bool isOrigin) const;
  void checkAnchorSide(const std::string& anchor) const;
  void finishMuscle();
  /// One 'key = value' line, in the block it belongs to.
  void readKey(const std::string& key, const std::string& value);
  void checkKeyBelongsHere(const std::string& key) const;
  void startMuscle(const std::string& value);
  void startFunction(const std::string& value);
  void readFunctionKey(const std::string& key, const std::string& value);
  void readMuscleKey(const std::string& key, const std::string& value);
  void readSetKey(const std::string& key, const std::string& value);

  fs::path file_;
  int line_ = 0;
  MuscleSet set_;
  MuscleDefinition* muscle_ = nullptr;
  ForceFunctionDefinition* function_ = nullptr;
  std::optional<double> muscleLoad_;
  std::map<std::string, int> seen_; // keys of the current block
  bool sideGiven_ = false;
  std::vector<std::pair<bool, bool>> ends_; // per function: origin, insertion given
  std::vector<bool> ownLoad_;
};

double Parser::number(const std::string& text, const std::string& what) const
{
  const std::string t = trim(text);
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || *end != '\0' || !std::isfinite(v))
    fail(what + ": '" + t + "' is not a number; write a plain decimal number such as 4.5 or 1.2e-5");
  return v;
}

void Parser::checkAnchorSide(const std::string& anchor) const
{
  if (!muscle_)
    return;
  if (muscle_->side == MuscleSide::Both && endsWith(anchor, "_right"))
    fail("'" + anchor +
         "': a side = both muscle is written for the patient's LEFT side (the right one is its "
         "mirror image); anchor it on " +
         mirroredName(anchor));
  if (muscle_->side == MuscleSide::Left && endsWith(anchor, "_right"))
    fail("'" + anchor + "' is on the right, but the muscle is side = left; use " + mirroredName(anchor) +
         " or make the muscle midline");
  if (muscle_->side == MuscleSide::Right && endsWith(anchor, "_left"))
    fail("'" + anchor + "' is on the left, but the muscle is side = right; use " + mirroredName(anchor) +
         " or make the muscle midline");
}

AttachmentDefinition Parser::point(const std::string& value, bool isOrigin) const
{
  const std::string end = isOrigin ? "origin" : "insertion";
  AttachmentDefinition p;
  p.line = line_;
  std::vector<std::string> parts;
  {
    std::stringstream in(value);
    std::string part;
    while (std::getline(in, part, ','))
      parts.push_back(trim(part));
  }
  if (parts.empty() || parts[0].empty())
    fail(end + ": expected 'LANDMARK, across MM, up MM, depth FRACTION|bone, radius MM', e.g. "
               "'cheilion_left, across 10, up 3, depth 0.35, radius 6'");
  const auto known = muscleAnchorNames();
  auto checkName = [&](const std::string& name) {
    if (std::find(known.begin(), known.end(), name) == known.end())
      fail(end + ": unknown landmark '" + name + "'; known: " + joined(known));
    checkAnchorSide(name);
  };
  {
    // "A" or "A to B at T"
    std::stringstream words(parts[0]);
    std::vector<std::string> w;
    std::string s;
    while (words >> s)
      w.push_back(s);
    if (w.size() == 1)
      p.anchor = w[0];
    else if (w.size() == 5 && w[1] == "to" && w[3] == "at")
    {
      p.anchor = w[0];
      p.towards = w[2];
      p.blend = number(w[4], end + " blend 'at'");
      if (p.blend < 0.0 || p.blend > 1.0)
        fail(end + ": 'at " + w[4] + "' must be a fraction from 0 (at " + w[0] + ") to 1 (at " + w[2] + ")");
    }
    else
      fail(end +
           ": the place must be a landmark ('cheilion_left') or a blend of two ('cheilion_left to "
           "labrale_superius at 0.5'), got '" +
           parts[0] + "'");
    checkName(p.anchor);
    if (!p.towards.empty())
      checkName(p.towards);
  }
  std::set<std::string> given;
  bool depthGiven = false, radiusGiven = false;
  for (std::size_t i = 1; i < parts.size(); ++i)
  {
    const auto space = parts[i].find_first_of(" \t");
    const std::string word = space == std::string::npos ? parts[i] : parts[i].substr(0, space);
    const std::string rest = space == std::string::npos ? std::string() : trim(parts[i].substr(space));
    if (word != "across" && word != "up" && word != "depth" && word != "radius")
      fail(end + ": unknown part '" + parts[i] +
           "'; after the landmark write 'across MM', 'up MM', "
           "'depth FRACTION' (or 'depth bone') and 'radius MM', separated by commas");
    if (!given.insert(word).second)
      fail(end + ": '" + word + "' is given twice");
    if (rest.empty())
      fail(end + ": '" + word + "' needs a value, e.g. '" + word + (word == "depth" ? " 0.4'" : " 5'"));
    if (word == "across")
      p.across = number(rest, end + " across");
    else if (word == "up")
      p.up = number(rest, end + " up");
    else if (word == "depth")
    {
      depthGiven = true;
      if (rest == "bone")
      {
        if (!isOrigin)
          fail("insertion: 'depth bone' is for an origin; an insertion pulls on the soft tissue: give a fraction "
               "from 0 (skin) to 1 (bone), e.g. 'depth 0.4'");
        p.inBone = true;
        p.depth = 1.0;
      }
      else
      {
        p.depth = number(rest, end + " depth");
        if (p.depth < 0.0 || p.depth > 1.0)
          fail(end + ": depth " + rest + " is outside 0 (skin) .. 1 (bone surface); write a fraction or 'bone'");
      }
    }
    else
    {
      radiusGiven = true;
      p.radius = number(rest, end + " radius");
      if (p.radius < 0.0)
        fail(end + ": radius " + rest + " is negative; write a radius in mm (0 for no force at an origin)");
    }
  }
  if (!depthGiven)
    fail(end + ": no depth; add 'depth FRACTION' (0 skin .. 1 bone)" +
         std::string(isOrigin ? " or 'depth bone' for an origin in bone" : ""));
  if (!isOrigin && (!radiusGiven || p.radius <= 0.0))
    fail("insertion: the insertion needs a radius > 0 (mm), e.g. 'radius 5': it is where the muscle pulls");
  if (isOrigin && p.inBone && p.radius > 0.0)
    fail("origin: an origin in bone applies no force on the soft tissue (thesis §4.6.2, r_o = 0); remove "
         "'radius' or give a depth fraction instead of 'bone'");
  if (isOrigin && !p.inBone && !radiusGiven)
    fail("origin: an origin in the soft tissue needs 'radius MM' (0 keeps it fixed, as an origin in bone)");
  return p;
}

void Parser::finishMuscle()
{
  if (!muscle_)
    return;
  if (muscle_->title.empty())
    fail("muscle '" + muscle_->id + "' has no title; add 'title = ...' after its 'muscle =' line", muscle_->line);
  if (!sideGiven_)
    fail("muscle '" + muscle_->id +
           "' has no side; add 'side = both' (left muscle mirrored to the right), "
           "'left', 'right' or 'midline'",
         muscle_->line);
  if (muscle_->functions.empty())
    fail("muscle '" + muscle_->id +
           "' has no force function; add 'function = NAME' with an origin, an "
           "insertion and a load",
         muscle_->line);
  for (std::size_t i = 0; i < muscle_->functions.size(); ++i)
  {
    auto& f = muscle_->functions[i];
    if (!ends_[i].first)
      fail("function '" + f.name + "' of muscle '" + muscle_->id + "' has no origin; add 'origin = LANDMARK, ...'",
           f.line);
    if (!ends_[i].second)
      fail("function '" + f.name + "' of muscle '" + muscle_->id +
             "' has no insertion; add 'insertion = "
             "LANDMARK, across MM, up MM, depth FRACTION, radius MM'",
           f.line);
    if (!ownLoad_[i])
    {
      if (!muscleLoad_)
        fail("function '" + f.name + "' of muscle '" + muscle_->id +
               "' has no load; add 'load = L' (N/mm^4) "
               "to the function or to the muscle before its first function",
             f.line);
      f.load = *muscleLoad_;
    }
    const auto& o = f.origin;
    const auto& n = f.insertion;
    if (o.anchor == n.anchor && o.towards == n.towards && o.blend == n.blend && o.across == n.across && o.up == n.up &&
        o.depth == n.depth)
      fail("function '" + f.name +
             "': the origin and the insertion are the same point; a muscle pulls its "
             "insertion towards its origin, so they must differ",
           f.line);
  }
}

namespace keys {
// The keys of each block of a muscle set file (data/muscles/README.md).
const std::set<std::string> set = {"muscle_set", "title", "reference", "load_scale", "muscle"};
const std::set<std::string> muscle = {"title", "side", "reference", "load", "load_scale", "function", "muscle"};
const std::set<std::string> function = {"origin", "insertion", "load", "falloff", "mirror", "function", "muscle"};
} // namespace keys

/// Lower case letters, digits and '_', starting with a letter.
bool isId(const std::string& text)
{
  static const std::regex idRe(R"(^[a-z][a-z0-9_]*$)");
  return std::regex_match(text, idRe);
}

MuscleSet Parser::run()
{
  std::ifstream in(file_);
  if (!in)
    fail("cannot be read; check the path", 0);
  set_.file = file_;
  std::string raw;
  while (std::getline(in, raw))
  {
    ++line_;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#')
      continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos)
      fail("expected 'key = value', got '" + line + "'");
    const std::string key = trim(line.substr(0, eq));
    std::string value = trim(line.substr(eq + 1));
    // A trailing comment after the value.
    if (const auto hash = value.find(" #"); hash != std::string::npos)
      value = trim(value.substr(0, hash));
    readKey(key, value);
  }
  finishMuscle();
  if (set_.muscles.empty())
    fail("no muscles; add 'muscle = ID' blocks (see data/muscles/README.md)", 0);
  if (set_.id.empty())
    set_.id = file_.stem().string();
  if (set_.title.empty())
    set_.title = set_.id;
  return set_;
}

void Parser::readKey(const std::string& key, const std::string& value)
{
  checkKeyBelongsHere(key);
  if (key == "muscle")
    return startMuscle(value);
  if (key == "function")
    return startFunction(value);
  if (auto [it, fresh] = seen_.emplace(key, line_); !fresh)
    fail("'" + key + "' is given twice here (first on line " + std::to_string(it->second) + ")");
  if (function_)
    readFunctionKey(key, value);
  else if (muscle_)
    readMuscleKey(key, value);
  else
    readSetKey(key, value);
}

/// A key of another block says where it belongs; an unknown one lists the
/// keys of the block it is in.
void Parser::checkKeyBelongsHere(const std::string& key) const
{
  const std::set<std::string>& allowed = function_ ? keys::function : muscle_ ? keys::muscle : keys::set;
  if (allowed.count(key))
    return;
  const bool known = keys::set.count(key) || keys::muscle.count(key) || keys::function.count(key);
  if (!known)
  {
    std::vector<std::string> names(allowed.begin(), allowed.end());
    fail("unknown key '" + key + "'; here the keys are: " + joined(names));
  }
  if (function_ && keys::muscle.count(key))
    fail("'" + key + "' belongs to the muscle: write it before the muscle's first 'function =' line");
  if (keys::function.count(key))
    fail("'" + key + "' belongs to a function: start one with " +
         std::string(muscle_ ? "" : "'muscle = ID' and then ") + "'function = NAME' first");
  if (keys::muscle.count(key) && !muscle_)
    fail("'" + key + "' belongs to a muscle: start one with 'muscle = ID' first");
  fail("'" + key + "' belongs at the top of the file, before the first 'muscle ='");
}

/// 'muscle = ID': the previous muscle finished (and checked), a new one begun.
void Parser::startMuscle(const std::string& value)
{
  finishMuscle();
  if (!isId(value))
    fail("muscle id '" + value + "' must be lower case letters, digits and '_' (e.g. zygomaticus_major)");
  if (endsWith(value, "_left") || endsWith(value, "_right"))
    fail("muscle id '" + value + "' must not end in _left or _right: the fit adds the side; say it with 'side ='");
  if (const MuscleDefinition* other = set_.find(value))
    fail("muscle '" + value + "' is defined twice (first on line " + std::to_string(other->line) + ")");
  set_.muscles.emplace_back();
  muscle_ = &set_.muscles.back();
  muscle_->id = value;
  muscle_->line = line_;
  function_ = nullptr;
  muscleLoad_.reset();
  sideGiven_ = false;
  ends_.clear();
  ownLoad_.clear();
  seen_.clear();
}

/// 'function = NAME': a new force function of the current muscle.
void Parser::startFunction(const std::string& value)
{
  if (!isId(value))
    fail("function name '" + value + "' must be lower case letters, digits and '_' (e.g. main, ala)");
  for (const auto& f : muscle_->functions)
    if (f.name == value)
      fail("function '" + value + "' is given twice in muscle '" + muscle_->id + "' (first on line " +
           std::to_string(f.line) + ")");
  muscle_->functions.emplace_back();
  function_ = &muscle_->functions.back();
  function_->name = value;
  function_->line = line_;
  ends_.emplace_back(false, false);
  ownLoad_.push_back(false);
  seen_.clear();
}

void Parser::readFunctionKey(const std::string& key, const std::string& value)
{
  if (key == "origin")
  {
    function_->origin = point(value, true);
    ends_.back().first = true;
  }
  else if (key == "insertion")
  {
    function_->insertion = point(value, false);
    ends_.back().second = true;
  }
  else if (key == "load")
  {
    function_->load = number(value, "load");
    if (function_->load <= 0.0)
      fail("load " + value + " must be > 0 (N/mm^4): a muscle pulls its insertion towards its origin");
    ownLoad_.back() = true;
  }
  else if (key == "falloff")
  {
    function_->falloff = number(value, "falloff");
    if (function_->falloff < 0.0)
      fail("falloff " + value + " is negative; write a width in mm (0 for the sharp sphere of eq. 4.41)");
  }
  else if (key == "mirror")
  {
    if (value != "yes" && value != "no")
      fail("mirror must be 'yes' or 'no', got '" + value + "'");
    function_->mirror = value == "yes";
    if (function_->mirror && muscle_->side != MuscleSide::Midline)
      fail("'mirror = yes' is for the functions of a midline muscle (half a ring written once); a side = " +
           std::string(sideName(muscle_->side)) + " muscle is mirrored as a whole by 'side = both'");
  }
}

void Parser::readMuscleKey(const std::string& key, const std::string& value)
{
  if (key == "title")
    muscle_->title = value;
  else if (key == "reference")
    muscle_->reference = value;
  else if (key == "side")
  {
    if (value == "left")
      muscle_->side = MuscleSide::Left;
    else if (value == "right")
      muscle_->side = MuscleSide::Right;
    else if (value == "both")
      muscle_->side = MuscleSide::Both;
    else if (value == "midline")
      muscle_->side = MuscleSide::Midline;
    else
      fail("side must be both (the left muscle, mirrored to the right), left, right or midline; got '" + value + "'");
    sideGiven_ = true;
  }
  else if (key == "load")
  {
    muscleLoad_ = number(value, "load");
    if (*muscleLoad_ <= 0.0)
      fail("load " + value + " must be > 0 (N/mm^4): a muscle pulls its insertion towards its origin");
  }
  else if (key == "load_scale")
  {
    muscle_->loadScale = number(value, "load_scale");
    if (muscle_->loadScale <= 0.0)
      fail("load_scale " + value + " must be > 0");
  }
}

void Parser::readSetKey(const std::string& key, const std::string& value)
{
  if (key == "muscle_set")
  {
    if (!isId(value))
      fail("muscle_set id '" + value + "' must be lower case letters, digits and '_' (e.g. default)");
    set_.id = value;
  }
  else if (key == "title")
    set_.title = value;
  else if (key == "reference")
    set_.reference = value;
  else if (key == "load_scale")
  {
    set_.loadScale = number(value, "load_scale");
    if (set_.loadScale <= 0.0)
      fail("load_scale " + value + " must be > 0");
  }
}

/// "FILE:LINE: message" ("FILE: message" for line 0), built with += (GCC 12
/// warns falsely on "literal" + std::to_string()).
std::string located(const fs::path& file, int line, const std::string& message)
{
  std::string text = file.string();
  if (line > 0)
  {
    text += ':';
    text += std::to_string(line);
  }
  text += ": ";
  text += message;
  return text;
}

} // namespace

MuscleSetFileError::MuscleSetFileError(const fs::path& file, int line, const std::string& message)
  : std::runtime_error(located(file, line, message)), file_(file), line_(line)
{}

const char* sideName(MuscleSide side)
{
  switch (side)
  {
  case MuscleSide::Left:
    return "left";
  case MuscleSide::Right:
    return "right";
  case MuscleSide::Both:
    return "both";
  case MuscleSide::Midline:
    return "midline";
  }
  return "?";
}

const MuscleDefinition* MuscleSet::find(const std::string& muscleId) const
{
  for (const auto& m : muscles)
    if (m.id == muscleId)
      return &m;
  return nullptr;
}

MuscleSet readMuscleSet(const fs::path& path)
{
  return Parser(path).run();
}

fs::path defaultMuscleSetPath()
{
  if (const char* env = std::getenv("CAPS_DATA_DIR"))
    return fs::path(env) / "muscles" / "default.muscles";
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
  {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "caps" / "data" / "muscles";
    if (fs::is_directory(installed, ec))
      return installed / "default.muscles";
  }
  return fs::path(CAPS_SOURCE_DATA_DIR) / "muscles" / "default.muscles";
}

std::vector<std::string> derivedAnchorNames()
{
  return {"stomion",           "cheilion_left",      "cheilion_right",   "eye_left",         "eye_right",
          "endocanthion_left", "endocanthion_right", "exocanthion_left", "exocanthion_right"};
}

std::vector<std::string> muscleAnchorNames()
{
  std::vector<std::string> names;
  for (const auto& d : seg::standardLandmarks())
    names.emplace_back(d.name);
  for (const auto& d : derivedAnchorNames())
    names.push_back(d);
  return names;
}

double faceSize(const std::vector<seg::Landmark>& landmarks)
{
  const seg::Landmark* nasion = findLandmark(landmarks, "nasion");
  const seg::Landmark* subnasale = findLandmark(landmarks, "subnasale");
  if (!nasion || !subnasale)
    throw std::invalid_argument("The face's size is its nasion–subnasale height, and these landmarks are missing: " +
                                std::string(!nasion ? "nasion" : "") + (!nasion && !subnasale ? ", " : "") +
                                (!subnasale ? "subnasale" : "") + ". Place them in the Range maps module.");
  const double height = nasion->z - subnasale->z;
  if (!(height >= 20.0))
    throw std::invalid_argument("The nasion is " + std::to_string(height) +
                                " mm above the subnasale (an adult's is about 53 mm); check the landmarks in the "
                                "Range maps module.");
  return height / kMeanNasionSubnasale;
}

namespace {

/// The median of the valid thicknesses (skin − bone) of the map samples
/// within @a radius mm of (θ, z) on the skin (@a skinRadius there); NaN if none.
template <class Valid>
double medianThicknessNear(const seg::RangeMap& skin, const seg::RangeMap& bone, double theta, double z,
                           double skinRadius, double radius, Valid valid)
{
  const seg::CylindricalFrame& frame = bone.frame();
  const double u = frame.thetaToIndex(theta), v = frame.zToIndex(z);
  const double du = skinRadius * frame.thetaStep(), dv = frame.zStep();
  const int ni = int(std::ceil(radius / du)), nj = int(std::ceil(radius / dv));
  std::vector<double> near;
  for (int j = int(std::floor(v)) - nj; j <= int(std::ceil(v)) + nj; ++j)
  {
    if (j < 0 || j >= frame.nZ())
      continue;
    for (int k = int(std::floor(u)) - ni; k <= int(std::ceil(u)) + ni; ++k)
    {
      const int i = ((k % frame.nTheta()) + frame.nTheta()) % frame.nTheta();
      const double t = double(skin.at(i, j)) - double(bone.at(i, j));
      if (valid(t) && std::pow((k - u) * du, 2) + std::pow((j - v) * dv, 2) <= radius * radius)
        near.push_back(t);
    }
  }
  if (near.empty())
    return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
  return near[near.size() / 2];
}

} // namespace

MuscleAnchors muscleAnchors(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin)
{
  MuscleAnchors out;
  out.size = faceSize(landmarks);
  const seg::Landmark* nasion = findLandmark(landmarks, "nasion");
  const double rn = skin.sample(nasion->theta, nasion->z);
  out.arcRadius = std::isfinite(rn) && rn > 20.0 ? rn : 90.0; // as planning::FaceLayout::scale
  for (const auto& l : landmarks)
    if (std::isfinite(l.theta) && std::isfinite(l.z))
      out.anchors.push_back(l);
  planning::FaceLayout f;
  try
  {
    f = planning::FaceLayout::fromLandmarks(landmarks, skin);
  }
  catch (const std::invalid_argument&)
  {
    return out; // no derived anchors; fitMuscleSet says why when it needs them
  }
  const double size = out.size; // FaceLayout's own: eyeOffset = 32 mm × size
  auto add = [&](const std::string& name, double across, double z) {
    out.anchors.push_back({name, f.frontTheta + across / f.scale, z});
  };
  add("stomion", 0.0, f.zStomion);
  add("cheilion_left", f.mouthHalfWidth, f.zStomion);
  add("cheilion_right", -f.mouthHalfWidth, f.zStomion);
  add("eye_left", f.eyeOffset, f.eyeZ);
  add("eye_right", -f.eyeOffset, f.eyeZ);
  // Farkas: intercanthal width about 32 mm, biocular width about 93 mm, so the
  // inner corner sits 16 mm and the outer about 15 mm from the eye's centre.
  add("endocanthion_left", f.eyeOffset - 16.0 * size, f.eyeZ);
  add("endocanthion_right", -(f.eyeOffset - 16.0 * size), f.eyeZ);
  add("exocanthion_left", f.eyeOffset + 15.0 * size, f.eyeZ);
  add("exocanthion_right", -(f.eyeOffset + 15.0 * size), f.eyeZ);
  return out;
}

AttachmentPlacement placeAttachment(const AttachmentDefinition& point, bool mirrored, const MuscleAnchors& anchors,
                                    const seg::RangeMap& skin, const seg::RangeMap& bone,
                                    const MuscleFitOptions& options)
{
  auto anchorOf = [&](const std::string& written) {
    const std::string name = mirrored ? mirroredName(written) : written;
    const seg::Landmark* l = findLandmark(anchors.anchors, name);
    if (!l)
      throw std::invalid_argument("its landmark " + name + " is missing");
    return *l;
  };
  const seg::Landmark a = anchorOf(point.anchor);
  double theta = a.theta, z = a.z;
  if (!point.towards.empty())
  {
    const seg::Landmark b = anchorOf(point.towards);
    // Blend in θ along the shorter way round.
    const double dTheta = seg::CylindricalFrame::wrapTheta(b.theta - a.theta);
    theta = a.theta + point.blend * dTheta;
    z = a.z + point.blend * (b.z - a.z);
  }
  z += point.up * anchors.size;
  const double dTheta = (mirrored ? -1.0 : 1.0) * point.across * anchors.size / anchors.arcRadius;
  if (std::abs(dTheta) > 0.5 * kPi)
    throw std::invalid_argument("its offset across runs more than a quarter of the way around the head");
  theta = seg::CylindricalFrame::wrapTheta(theta + dTheta);

  AttachmentPlacement p;
  p.theta = theta;
  p.z = z;
  p.skinRadius = skin.sample(theta, z);
  if (!std::isfinite(p.skinRadius))
  {
    std::ostringstream where;
    where.precision(4);
    where << "it falls off the skin map (no skin at θ " << theta * 180.0 / kPi << "°, z " << z << " mm)";
    throw std::invalid_argument(where.str());
  }

  // Soft-tissue thickness: measured at the point where it agrees with the
  // median of the measured samples close by; else that median (it bridges
  // small holes of the bone map, and a ray through a thin wall that found
  // the bone behind it: the zygomatic bone's, 15 mm deeper on one side of
  // the sample CT); else the default.
  auto valid = [&](double t) { return std::isfinite(t) && t > 0.0 && t <= options.maximumThickness; };
  p.source = ThicknessSource::Default;
  p.thickness = options.defaultThickness;
  if (!bone.empty())
  {
    const double here = p.skinRadius - bone.sample(theta, z);
    const double nearby = medianThicknessNear(skin, bone, theta, z, p.skinRadius, options.boneSearch, valid);
    constexpr double kAgrees = 3.0; // mm, or 30 % of the median
    if (valid(here) && !(std::abs(here - nearby) > std::max(kAgrees, 0.3 * nearby)))
    {
      p.thickness = here;
      p.source = ThicknessSource::Measured;
    }
    else if (std::isfinite(nearby))
    {
      p.thickness = nearby;
      p.source = ThicknessSource::Nearby;
    }
  }
  p.r = p.skinRadius - (point.inBone ? 1.0 : point.depth) * p.thickness;
  p.position = skin.frame().toWorld(p.r, theta, z);
  return p;
}

namespace {

/// Refuses a set whose landmarks are not all placed, naming each missing one
/// with the first muscle that needs it.
void checkLandmarksPlaced(const MuscleSet& set, const std::vector<seg::Landmark>& landmarks, bool& derived)
{
  // Which landmarks the set needs, each with the first muscle that needs it.
  std::vector<std::pair<std::string, std::string>> needed = {{"nasion", "the face's size"},
                                                             {"subnasale", "the face's size"}};
  derived = false;
  auto need = [&](const std::string& name, const std::string& by) {
    if (isDerived(name))
      derived = true;
    else if (std::none_of(needed.begin(), needed.end(), [&](const auto& n) { return n.first == name; }))
      needed.emplace_back(name, by);
  };
  for (const auto& m : set.muscles)
    for (const auto& f : m.functions)
      for (const AttachmentDefinition* p : {&f.origin, &f.insertion})
        for (const std::string& name : {p->anchor, p->towards})
        {
          if (name.empty())
            continue;
          need(name, m.id);
          if (m.side == MuscleSide::Both || f.mirror)
            need(mirroredName(name), m.id);
        }
  if (derived)
    for (const char* name : {"glabella", "pronasale", "labrale_superius", "labrale_inferius"})
      need(name, "the mouth and eye anchors");
  std::string missing;
  for (const auto& [name, by] : needed)
    if (!findLandmark(landmarks, name))
      missing += (missing.empty() ? "" : ", ") + name + " (for " + by + ")";
  if (derived && !findLandmark(landmarks, "menton") && !findLandmark(landmarks, "pogonion"))
    missing += std::string(missing.empty() ? "" : ", ") + "menton or pogonion (for the mouth and eye anchors)";
  if (!missing.empty())
    throw std::invalid_argument("The muscle set '" + set.id +
                                "' is placed by facial landmarks, and these are "
                                "missing: " +
                                missing + ". Place them in the Range maps module (or run it again to find them).");
}

/// The muscle's instances: both sides (the right one mirrored), one side, or
/// the midline.
std::vector<std::pair<std::string, bool>> instancesOf(const MuscleDefinition& m)
{
  switch (m.side)
  {
  case MuscleSide::Both:
    return {{"left", false}, {"right", true}};
  case MuscleSide::Left:
    return {{"left", false}};
  case MuscleSide::Right:
    return {{"right", false}};
  case MuscleSide::Midline:
    return {{"midline", false}};
  }
  return {};
}

/// One force function @a f of muscle @a m placed on the patient as
/// @a name (mirrored or not), added to @a fm.
void placeFunction(const MuscleSet& set, const MuscleDefinition& m, const ForceFunctionDefinition& f,
                   const std::string& name, bool mirrored, const MuscleAnchors& anchors, const seg::RangeMap& skin,
                   const seg::RangeMap& bone, const MuscleFitOptions& options, FittedMuscle& fm)
{
  const double size = anchors.size;
  auto place = [&](const AttachmentDefinition& p, const char* end) {
    try
    {
      return placeAttachment(p, mirrored, anchors, skin, bone, options);
    }
    catch (const std::invalid_argument& e)
    {
      std::string where =
        set.file.empty() ? std::string() : " (" + set.file.string() + ":" + std::to_string(p.line) + ")";
      throw std::invalid_argument("The " + std::string(end) + " of " + fm.id + " function " + name + where +
                                  " cannot be placed on this patient: " + e.what() +
                                  ". Check the landmarks, or move the point in the muscle file.");
    }
  };
  const AttachmentPlacement o = place(f.origin, "origin");
  const AttachmentPlacement i = place(f.insertion, "insertion");
  fem::Muscle muscle;
  muscle.name = fm.id + "." + name;
  muscle.origin = o.position;
  muscle.originRadius = f.origin.inBone ? 0.0 : f.origin.radius * size;
  muscle.insertion = i.position;
  muscle.insertionRadius = f.insertion.radius * size;
  // Loads are written for the adult mean face. The body force of
  // eq. 4.40 grows with the length |p_o − p_i| (× size) and the soft
  // tissue's displacement under a body force with the square of its
  // extent, so l / size² gives a scaled face the same strains: the
  // same expression.
  muscle.load = f.load * m.loadScale * set.loadScale / (size * size);
  muscle.falloff = f.falloff * size;
  fem::validateMuscle(muscle, fm.functions.size());
  fm.functions.push_back(muscle);
  fm.placements.emplace_back(o, i);
}

} // namespace

std::vector<FittedMuscle> fitMuscleSet(const MuscleSet& set, const std::vector<seg::Landmark>& landmarks,
                                       const seg::RangeMap& skin, const seg::RangeMap& bone,
                                       const MuscleFitOptions& options)
{
  if (!bone.empty() && bone.frame() != skin.frame())
    throw std::invalid_argument("The skin and bone range maps are on different cylindrical frames; make them "
                                "again together in the Range maps module.");
  bool derived = false;
  checkLandmarksPlaced(set, landmarks, derived);
  const MuscleAnchors anchors = muscleAnchors(landmarks, skin);
  if (derived && !findLandmark(anchors.anchors, "stomion"))
  {
    try
    {
      (void)planning::FaceLayout::fromLandmarks(landmarks, skin);
    }
    catch (const std::invalid_argument& e)
    {
      throw std::invalid_argument(std::string("The mouth and eye anchors of the muscles cannot be placed: ") +
                                  e.what());
    }
  }

  std::vector<FittedMuscle> out;
  for (const auto& m : set.muscles)
    for (const auto& [side, instanceMirrored] : instancesOf(m))
    {
      FittedMuscle fm;
      fm.definition = m.id;
      fm.side = side;
      fm.id = m.side == MuscleSide::Midline ? m.id : m.id + "_" + side;
      fm.title = m.side == MuscleSide::Midline ? m.title : m.title + " (" + side + ")";
      for (const auto& f : m.functions)
      {
        std::vector<std::pair<std::string, bool>> copies;
        if (f.mirror)
          copies = {{f.name + "_left", instanceMirrored}, {f.name + "_right", !instanceMirrored}};
        else
          copies = {{f.name, instanceMirrored}};
        for (const auto& [name, mirrored] : copies)
          placeFunction(set, m, f, name, mirrored, anchors, skin, bone, options, fm);
      }
      out.push_back(std::move(fm));
    }
  return out;
}

} // namespace caps::expression
