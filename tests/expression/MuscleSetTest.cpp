// Muscle sets (thesis §4.6.2, §5.3): the file format and
// its error messages, the fit of the default set on an analytic cylinder
// face (exact mirror images, exact scaling with the face, exact depths) and
// on the sample CT's face (every muscle there, attachments in the soft
// tissue, pull directions as the anatomy says, forces of the order of 1 N,
// and each muscle moving the skin of the whole-face model the right way).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "expression/SampleFace.h"
#include "fem/StaticAnalysis.h"
#include "planning/FaceModel.h"
#include "planning/MuscleResponses.h"
#include "planning/MuscleSet.h"
#include "planning/SkinTensionLines.h"

using namespace caps;
using namespace caps::expression;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFront = -kPi / 2.0;

// ---- an analytic face: skin a cylinder of radius 90 mm, bone 12 mm under it

constexpr double kSkinR = 90.0;
constexpr double kThick = 12.0;

struct CylinderFace
{
  seg::RangeMap skin, bone;
  std::vector<seg::Landmark> landmarks;
};

/// Landmarks at average adult heights (Farkas) on the cylinder, θ from arcs.
std::vector<seg::Landmark> cylinderLandmarks()
{
  auto at = [](const char* name, double arc, double z) { return seg::Landmark{name, kFront + arc / kSkinR, z}; };
  return {at("glabella", 0, 15),           at("nasion", 0, 0),
          at("pronasale", 0, -35),         at("subnasale", 0, -53),
          at("mid_philtrum", 0, -60),      at("labrale_superius", 0, -65),
          at("labrale_inferius", 0, -80),  at("pogonion", 0, -95),
          at("menton", 0, -117),           at("zygion_left", 65, -20),
          at("zygion_right", -65, -20),    at("gonion_left", 50, -75),
          at("gonion_right", -50, -75),    at("mid_cheek_left", 45, -35),
          at("mid_cheek_right", -45, -35), at("forehead", 0, 40)};
}

const CylinderFace& cylinderFace()
{
  static const CylinderFace face = [] {
    const seg::CylindricalFrame frame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -150.0, 100.0, 512, 251);
    return CylinderFace{seg::RangeMap(frame, float(kSkinR)), seg::RangeMap(frame, float(kSkinR - kThick)),
                        cylinderLandmarks()};
  }();
  return face;
}

/// Landmarks scaled about the nasion by @a k in θ and z.
std::vector<seg::Landmark> scaledAboutNasion(std::vector<seg::Landmark> landmarks, double k)
{
  const seg::Landmark nasion =
    *std::find_if(landmarks.begin(), landmarks.end(), [](const auto& l) { return l.name == "nasion"; });
  for (auto& l : landmarks)
  {
    l.theta = nasion.theta + k * (l.theta - nasion.theta);
    l.z = nasion.z + k * (l.z - nasion.z);
  }
  return landmarks;
}

const FittedMuscle* findMuscle(const std::vector<FittedMuscle>& muscles, const std::string& id)
{
  for (const auto& m : muscles)
    if (m.id == id)
      return &m;
  return nullptr;
}

const MuscleSet& defaultSet()
{
  static const MuscleSet set = readMuscleSet(defaultMuscleSetPath());
  return set;
}

const std::vector<FittedMuscle>& sampleMuscles()
{
  static const std::vector<FittedMuscle> muscles = [] {
    const auto& face = test::sampleFace();
    return fitMuscleSet(defaultSet(), face.landmarks.landmarks, face.maps.skin, face.maps.bone);
  }();
  return muscles;
}

/// The mirror image of a world point about the plane through the frame's axis
/// and the direction θ.
Eigen::Vector3d mirrored(const seg::CylindricalFrame& frame, double theta, const Eigen::Vector3d& p)
{
  const Eigen::Vector3d n = frame.radialDirection(theta + kPi / 2.0);
  return p - 2.0 * (p - frame.origin()).dot(n) * n;
}

/// Pairs each function of a left muscle with its right twin: for a
/// side = both muscle, X_left / X_right; for a mirrored midline function,
/// NAME_left / NAME_right within the muscle.
std::vector<std::pair<const fem::Muscle*, const fem::Muscle*>> mirrorPairs(const std::vector<FittedMuscle>& muscles)
{
  std::vector<std::pair<const fem::Muscle*, const fem::Muscle*>> pairs;
  auto strip = [](const std::string& name) { return name.substr(name.find('.')); };
  for (const auto& m : muscles)
  {
    if (m.side == "left")
    {
      const FittedMuscle* right = findMuscle(muscles, m.definition + "_right");
      EXPECT_NE(right, nullptr) << m.id;
      if (!right)
        continue;
      EXPECT_EQ(right->functions.size(), m.functions.size());
      for (std::size_t i = 0; i < m.functions.size() && i < right->functions.size(); ++i)
      {
        EXPECT_EQ(strip(m.functions[i].name), strip(right->functions[i].name));
        pairs.emplace_back(&m.functions[i], &right->functions[i]);
      }
    }
    else if (m.side == "midline")
      for (const auto& f : m.functions)
        if (f.name.size() > 5 && f.name.compare(f.name.size() - 5, 5, "_left") == 0)
        {
          const std::string twin = f.name.substr(0, f.name.size() - 5) + "_right";
          const auto it =
            std::find_if(m.functions.begin(), m.functions.end(), [&](const fem::Muscle& g) { return g.name == twin; });
          EXPECT_NE(it, m.functions.end()) << twin;
          if (it != m.functions.end())
            pairs.emplace_back(&f, &*it);
        }
  }
  return pairs;
}

/// The file's definition of a fitted function ("MUSCLE.NAME", or
/// "MUSCLE.NAME_left/_right" for a mirrored function of a midline muscle).
const ForceFunctionDefinition& definitionOf(const FittedMuscle& muscle, const fem::Muscle& function)
{
  const MuscleDefinition* def = defaultSet().find(muscle.definition);
  EXPECT_NE(def, nullptr) << muscle.definition;
  const std::string name = function.name.substr(function.name.find('.') + 1);
  for (const auto& f : def->functions)
    if (f.name == name || (f.mirror && (name == f.name + "_left" || name == f.name + "_right")))
      return f;
  ADD_FAILURE() << "no definition of " << function.name;
  return def->functions.front();
}

/// Tissue volume (mm^3) of a sphere: grid points inside the sphere lying
/// between the bone and the skin (where the bone map has no valid bone, up
/// to 12 mm under the skin), read straight from the maps.
double tissueVolume(const seg::RangeMap& skin, const seg::RangeMap& bone, const Eigen::Vector3d& c, double radius)
{
  const int n = 12;
  const double h = radius / n;
  int inside = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k)
      {
        const Eigen::Vector3d d(i * h, j * h, k * h);
        if (d.norm() >= radius)
          continue;
        const seg::CylindricalPoint q = skin.frame().toCylindrical(c + d);
        const double rs = skin.sample(q.theta, q.z), rb = bone.sample(q.theta, q.z);
        const double inner = std::isfinite(rb) && rs - rb > 0.0 && rs - rb <= 30.0 ? rb : rs - 12.0;
        if (q.r < rs && q.r > inner)
          ++inside;
      }
  return inside * h * h * h;
}

fs::path writeFile(const std::string& name, const std::string& text)
{
  const fs::path folder = fs::temp_directory_path() / "caps-muscle-set-test";
  fs::create_directories(folder);
  const fs::path file = folder / name;
  std::ofstream(file) << text;
  return file;
}

const char* kGood = R"(# a small set written by a test
muscle_set = test
title = Test muscles
load_scale = 2
muscle = zygomaticus_major
title = Zygomaticus major
side = both
reference = a test
load = 2.5e-5
load_scale = 3
function = main
origin = zygion_left, across -15, up -8, depth bone
insertion = cheilion_left, across 10, up 3, depth 0.35, radius 6
)";

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos)
    text.replace(at, from.size(), to);
  return text;
}

/// The error of reading @a text; "" when it reads.
std::string readError(const std::string& name, const std::string& text)
{
  try
  {
    readMuscleSet(writeFile(name, text));
  }
  catch (const MuscleSetFileError& e)
  {
    return e.what();
  }
  return "";
}

} // namespace

// ---- the file format

TEST(MuscleSetFile, ReadsASmallSetAndMultipliesTheLoadScales)
{
  const MuscleSet set = readMuscleSet(writeFile("good.muscles", kGood));
  EXPECT_EQ(set.id, "test");
  EXPECT_EQ(set.title, "Test muscles");
  ASSERT_EQ(set.muscles.size(), 1u);
  const MuscleDefinition& m = set.muscles[0];
  EXPECT_EQ(m.side, MuscleSide::Both);
  ASSERT_EQ(m.functions.size(), 1u);
  EXPECT_EQ(m.functions[0].origin.anchor, "zygion_left");
  EXPECT_TRUE(m.functions[0].origin.inBone);
  EXPECT_DOUBLE_EQ(m.functions[0].insertion.across, 10.0);
  EXPECT_DOUBLE_EQ(m.functions[0].insertion.depth, 0.35);
  EXPECT_DOUBLE_EQ(m.functions[0].load, 2.5e-5); // the muscle's load, for its function

  const auto& face = cylinderFace();
  const auto fitted = fitMuscleSet(set, face.landmarks, face.skin, face.bone);
  ASSERT_EQ(fitted.size(), 2u);
  EXPECT_EQ(fitted[0].id, "zygomaticus_major_left");
  EXPECT_EQ(fitted[0].title, "Zygomaticus major (left)");
  EXPECT_EQ(fitted[1].id, "zygomaticus_major_right");
  EXPECT_NEAR(fitted[0].functions[0].load, 2.5e-5 * 2.0 * 3.0, 1e-18);
  EXPECT_EQ(fitted[0].functions[0].originRadius, 0.0);
  EXPECT_NEAR(fitted[0].functions[0].insertionRadius, 6.0, 1e-12); // the cylinder face has the mean size
}

TEST(MuscleSetFile, ErrorsNameTheLineAndTheFix)
{
  struct Case
  {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
    {"insertion = cheilion_left,", "insertion = cheilion_middle,",
     ":13: insertion: unknown landmark 'cheilion_middle'; known: supraglabella, glabella"},
    {"insertion = cheilion_left, across 10, up 3, depth 0.35, radius 6\n", "",
     ":11: function 'main' of muscle 'zygomaticus_major' has no insertion; add 'insertion = LANDMARK"},
    {"radius 6", "radius -6", ":13: insertion: radius -6 is negative"},
    {"across 10,", "across 1O,", ":13: insertion across: '1O' is not a number; write a plain decimal number"},
    {"load = 2.5e-5", "load = lots", ":9: load: 'lots' is not a number"},
    {"reference = a test", "refrence = a test", ":8: unknown key 'refrence'; here the keys are:"},
    {"origin = zygion_left,", "origin = zygion_right,",
     ":12: 'zygion_right': a side = both muscle is written for the "
     "patient's LEFT side"},
    {"side = both", "side = across", ":7: side must be both"},
    {"depth 0.35", "depth bone", ":13: insertion: 'depth bone' is for an origin"},
    {"depth bone", "depth 1.5", ":12: origin: depth 1.5 is outside 0 (skin) .. 1 (bone surface)"},
    {"depth bone", "depth bone, radius 3", ":12: origin: an origin in bone applies no force"},
    {"function = main\n", "", ":11: 'origin' belongs to a function: start one with 'function = NAME' first"},
    {"title = Zygomaticus major\n", "", ":5: muscle 'zygomaticus_major' has no title"},
    {"load = 2.5e-5\n", "", ":10: function 'main' of muscle 'zygomaticus_major' has no load; add 'load = L'"},
    {"side = both", "side = both\nmirror = yes", ":8: 'mirror' belongs to a function"},
    {"function = main", "function = main\nmirror = yes",
     ":12: 'mirror = yes' is for the functions of a midline muscle"},
    {"muscle = zygomaticus_major", "muscle = zygomaticus_major_left",
     ":5: muscle id 'zygomaticus_major_left' must not "
     "end in _left or _right"},
    {"across -15, up -8", "across -15, up -8, sideways 3", ":12: origin: unknown part 'sideways 3'"},
  };
  for (const auto& c : cases)
  {
    const std::string message = readError("bad.muscles", replaced(kGood, c.from, c.to));
    EXPECT_NE(message.find("bad.muscles" + c.expected), std::string::npos) << "for '" << c.to << "' got: " << message;
  }
  // A file with no muscles, and no file at all.
  EXPECT_NE(readError("empty.muscles", "# nothing\nmuscle_set = empty\n").find("empty.muscles: no muscles; add"),
            std::string::npos);
  EXPECT_THROW(readMuscleSet("/nonexistent/x.muscles"), MuscleSetFileError);
}

TEST(MuscleSetFile, MissingLandmarksAreNamed)
{
  const auto& face = cylinderFace();
  std::vector<seg::Landmark> landmarks;
  for (const auto& l : face.landmarks)
    if (l.name != "zygion_right" && l.name != "menton")
      landmarks.push_back(l);
  try
  {
    fitMuscleSet(defaultSet(), landmarks, face.skin, face.bone);
    FAIL() << "no error";
  }
  catch (const std::invalid_argument& e)
  {
    const std::string m = e.what();
    EXPECT_NE(m.find("missing: "), std::string::npos) << m;
    EXPECT_NE(m.find("zygion_right (for zygomaticus_major)"), std::string::npos) << m;
    EXPECT_NE(m.find("menton (for depressor_labii_inferioris)"), std::string::npos) << m;
    EXPECT_EQ(m.find("zygion_left"), std::string::npos) << m;
    EXPECT_NE(m.find("Range maps module"), std::string::npos) << m;
  }
}

TEST(MuscleSetFile, APointOffTheSkinIsNamed)
{
  const auto& face = cylinderFace();
  seg::RangeMap holed = face.skin;
  // No skin beyond 45° to the patient's left of the front: the risorius's
  // origin (50 mm past the mouth corner) and the temporalis are off the map.
  for (int j = 0; j < holed.nZ(); ++j)
    for (int i = 0; i < holed.nTheta(); ++i)
      if (holed.frame().indexToTheta(i) > kFront + 45.0 * kPi / 180.0 && holed.frame().indexToTheta(i) < 0.5)
        holed.at(i, j) = seg::RangeMap::quietNaN();
  try
  {
    fitMuscleSet(defaultSet(), face.landmarks, holed, face.bone);
    FAIL() << "no error";
  }
  catch (const std::invalid_argument& e)
  {
    const std::string m = e.what();
    EXPECT_NE(m.find("cannot be placed on this patient"), std::string::npos) << m;
    EXPECT_NE(m.find("skin"), std::string::npos) << m;
    EXPECT_NE(m.find("default.muscles:"), std::string::npos) << m;
  }
}

// ---- the construction, exactly, on the analytic cylinder face

TEST(MuscleSetCylinder, RightMusclesAreTheMirrorImagesOfTheLeft)
{
  const auto& face = cylinderFace();
  const auto muscles = fitMuscleSet(defaultSet(), face.landmarks, face.skin, face.bone);
  const auto pairs = mirrorPairs(muscles);
  EXPECT_EQ(pairs.size(), 7u + 1u + 3u + 3u); // 6 both-sided muscles (7 functions), corrugator, 2 rings
  for (const auto& [l, r] : pairs)
  {
    EXPECT_LT((mirrored(face.skin.frame(), kFront, l->origin) - r->origin).norm(), 1e-6) << l->name;
    EXPECT_LT((mirrored(face.skin.frame(), kFront, l->insertion) - r->insertion).norm(), 1e-6) << l->name;
    EXPECT_EQ(l->insertionRadius, r->insertionRadius);
    EXPECT_EQ(l->load, r->load);
    // and the left one is on the left (LPS +x), at least at its insertion
    EXPECT_GT(l->insertion.x(), 0.0) << l->name;
  }
}

TEST(MuscleSetCylinder, DepthsAreFractionsOfTheSoftTissue)
{
  const auto& face = cylinderFace();
  const auto muscles = fitMuscleSet(defaultSet(), face.landmarks, face.skin, face.bone);
  for (const auto& m : muscles)
  {
    for (const auto& f : m.functions)
    {
      const ForceFunctionDefinition& d = definitionOf(m, f);
      const double rOrigin = Eigen::Vector2d(f.origin.x(), f.origin.y()).norm();
      const double rInsertion = Eigen::Vector2d(f.insertion.x(), f.insertion.y()).norm();
      EXPECT_NEAR(rOrigin, kSkinR - (d.origin.inBone ? 1.0 : d.origin.depth) * kThick, 1e-4) << f.name;
      EXPECT_NEAR(rInsertion, kSkinR - d.insertion.depth * kThick, 1e-4) << f.name;
    }
  }
}

TEST(MuscleSetCylinder, AttachmentsScaleWithTheFace)
{
  const auto& face = cylinderFace();
  const double k = 1.1;
  const auto base = fitMuscleSet(defaultSet(), face.landmarks, face.skin, face.bone);
  const auto big = fitMuscleSet(defaultSet(), scaledAboutNasion(face.landmarks, k), face.skin, face.bone);
  ASSERT_EQ(base.size(), big.size());
  const seg::CylindricalFrame& frame = face.skin.frame();
  // Face-plane coordinates about the nasion: arc on the skin and height.
  auto plane = [&](const Eigen::Vector3d& p) {
    const seg::CylindricalPoint c = frame.toCylindrical(p);
    return Eigen::Vector3d(kSkinR * seg::CylindricalFrame::wrapTheta(c.theta - kFront), c.z, c.r);
  };
  int checked = 0;
  for (std::size_t m = 0; m < base.size(); ++m)
    for (std::size_t f = 0; f < base[m].functions.size(); ++f)
    {
      const fem::Muscle& a = base[m].functions[f];
      const fem::Muscle& b = big[m].functions[f];
      for (const auto& [pa, pb] : {std::pair{a.origin, b.origin}, std::pair{a.insertion, b.insertion}})
      {
        const Eigen::Vector3d qa = plane(pa), qb = plane(pb);
        EXPECT_NEAR(qb.x(), k * qa.x(), 1e-9) << a.name; // arc from the midline
        EXPECT_NEAR(qb.y(), k * qa.y(), 1e-9) << a.name; // height from the nasion
        EXPECT_NEAR(qb.z(), qa.z(), 1e-6) << a.name;     // depth is a fraction of the tissue
      }
      EXPECT_NEAR(b.insertionRadius, k * a.insertionRadius, 1e-12);
      EXPECT_NEAR(b.originRadius, k * a.originRadius, 1e-12);
      EXPECT_NEAR(b.load, a.load / (k * k), 1e-15) << a.name << ": the same strains on the bigger face";
      ++checked;
    }
  EXPECT_GT(checked, 20);
}

// ---- the default set on the sample CT's face

TEST(MuscleSetSample, EveryMuscleOfTheIssueIsThereOnBothSides)
{
  const auto& muscles = sampleMuscles();
  for (const char* id : {"levator_labii_superioris", "temporalis", "risorius", "levator_labii_superioris_alaeque_nasi",
                         "depressor_labii_inferioris", "zygomaticus_major"})
    for (const char* side : {"_left", "_right"})
    {
      const FittedMuscle* m = findMuscle(muscles, std::string(id) + side);
      ASSERT_NE(m, nullptr) << id << side;
      EXPECT_FALSE(m->functions.empty());
      EXPECT_EQ(m->functions.size(), m->placements.size());
    }
  const FittedMuscle* corrugator = findMuscle(muscles, "corrugator_supercilii");
  ASSERT_NE(corrugator, nullptr);
  EXPECT_EQ(corrugator->functions.size(), 2u); // one function per brow
  for (const char* id : {"orbicularis_oris_upper", "orbicularis_oris_lower"})
  {
    const FittedMuscle* ring = findMuscle(muscles, id);
    ASSERT_NE(ring, nullptr) << id;
    EXPECT_EQ(ring->functions.size(), 6u) << id; // three links per half lip
  }
  EXPECT_EQ(muscles.size(), 15u);
}

TEST(MuscleSetSample, MirroredLandmarksGiveMirroredMuscles)
{
  // The sample face is not symmetric, so mirror its landmarks first (right :=
  // left mirrored about the nasion's θ, midline landmarks onto that θ): the
  // construction must then give mirrored muscles up to the skin's own
  // asymmetry (offsets are arcs along the real skin; depths fractions of the
  // real tissue).
  const auto& face = test::sampleFace();
  std::vector<seg::Landmark> landmarks = face.landmarks.landmarks;
  const double front = face.landmarks.find("nasion")->theta;
  for (auto& l : landmarks)
  {
    const std::string& n = l.name;
    if (n.size() > 6 && n.compare(n.size() - 6, 6, "_right") == 0)
    {
      const seg::Landmark* left = face.landmarks.find(n.substr(0, n.size() - 6) + "_left");
      ASSERT_NE(left, nullptr);
      l = {n, 2.0 * front - left->theta, left->z};
    }
    else if (n.find("_left") == std::string::npos)
      l.theta = front;
  }
  const auto muscles = fitMuscleSet(defaultSet(), landmarks, face.maps.skin, face.maps.bone);
  const auto& frame = face.maps.skin.frame();
  // The placements of each function by name, to compare the twins.
  std::map<const fem::Muscle*, std::pair<AttachmentPlacement, AttachmentPlacement>> placed;
  for (const auto& m : muscles)
    for (std::size_t f = 0; f < m.functions.size(); ++f)
      placed[&m.functions[f]] = m.placements[f];
  double worst = 0.0;
  std::string worstName;
  int pairs = 0;
  for (const auto& [l, r] : mirrorPairs(muscles))
  {
    ++pairs;
    const auto& pl = placed.at(l);
    const auto& pr = placed.at(r);
    for (const auto& [a, b] : {std::pair{pl.first, pr.first}, std::pair{pl.second, pr.second}})
    {
      // The construction: θ mirrored about the nasion's, the same height, the
      // same fraction of the soft tissue, exactly.
      EXPECT_NEAR(seg::CylindricalFrame::wrapTheta(b.theta - front), -seg::CylindricalFrame::wrapTheta(a.theta - front),
                  1e-9)
        << l->name;
      EXPECT_NEAR(a.z, b.z, 1e-9) << l->name;
      EXPECT_NEAR((a.skinRadius - a.r) / a.thickness, (b.skinRadius - b.r) / b.thickness, 1e-9) << l->name;
      EXPECT_NEAR(frame.toCylindrical(a.position).z, a.z, 1e-9);
      // The face itself: how far the right point is from the mirrored left
      // one (the skin's and the bone's asymmetry), for information.
      const double d = (mirrored(frame, front, a.position) - b.position).norm();
      if (d > worst)
      {
        worst = d;
        worstName = l->name;
      }
      // Loose: the sample's skin and bone differ between the sides by a few
      // mm; a point on the nose's side wall or through a hole of the bone
      // map on one side only would be much further off.
      EXPECT_LT(d, 6.0) << l->name;
    }
  }
  EXPECT_EQ(pairs, 14);
  std::printf("[ mirror ] worst distance right vs mirrored left: %.2f mm (%s)\n", worst, worstName.c_str());
}

TEST(MuscleSetSample, AttachmentsLieInTheSoftTissueAndOriginsOnTheBone)
{
  const auto& face = test::sampleFace();
  const auto& skin = face.maps.skin;
  const auto& bone = face.maps.bone;
  int measured = 0, total = 0;
  for (const auto& m : sampleMuscles())
    for (std::size_t f = 0; f < m.functions.size(); ++f)
    {
      const fem::Muscle& fn = m.functions[f];
      const auto& [origin, insertion] = m.placements[f];
      for (const auto& [p, radius, world] :
           {std::tuple{origin, fn.originRadius, fn.origin}, std::tuple{insertion, fn.insertionRadius, fn.insertion}})
      {
        ++total;
        const seg::CylindricalPoint c = skin.frame().toCylindrical(world);
        EXPECT_NEAR(c.z, p.z, 1e-9);
        const double rs = skin.sample(c.theta, c.z), rb = bone.sample(c.theta, c.z);
        ASSERT_TRUE(std::isfinite(rs)) << fn.name;
        EXPECT_LE(c.r, rs + 1e-9) << fn.name; // never outside the skin
        const bool boneHere = std::isfinite(rb) && rs - rb > 0.0 && rs - rb <= 30.0;
        if (boneHere)
        {
          ++measured;
          EXPECT_EQ(p.source, ThicknessSource::Measured) << fn.name;
          EXPECT_GE(c.r, rb - 1e-9) << fn.name; // never inside the bone
          if (&p == &origin && definitionOf(m, fn).origin.inBone)
          {
            EXPECT_NEAR(c.r, rb, 1e-6) << fn.name << ": an origin in bone lies on the bone surface";
          }
          if (radius > 0.0)
          {
            EXPECT_GT(c.r, rb) << fn.name;
            EXPECT_LT(c.r, rs) << fn.name;
          }
        }
        else
        {
          EXPECT_NE(p.source, ThicknessSource::Measured) << fn.name;
          EXPECT_LE(rs - c.r, 30.0) << fn.name;
          if (radius > 0.0)
          {
            EXPECT_LT(c.r, rs) << fn.name;
          }
        }
      }
    }
  std::printf("[ tissue ] %d of %d attachments on measured bone, the others bridged or at the default depth\n",
              measured, total);
  EXPECT_GT(measured, total / 3);
}

TEST(MuscleSetSample, MusclesPullAsTheAnatomySays)
{
  const auto& face = test::sampleFace();
  const auto& frame = face.maps.skin.frame();
  const double front = face.landmarks.find("nasion")->theta;
  // The pull on the insertion (origin − insertion) in the face's local axes
  // at the insertion: up along the head axis, lateral away from the midline.
  struct Pull
  {
    double up, lateral, length;
  };
  auto pull = [&](const fem::Muscle& f) {
    const seg::CylindricalPoint c = frame.toCylindrical(f.insertion);
    const double side = seg::CylindricalFrame::wrapTheta(c.theta - front) > 0.0 ? 1.0 : -1.0;
    const Eigen::Vector3d d = f.origin - f.insertion;
    return Pull{d.dot(frame.direction()), side * d.dot(frame.radialDirection(c.theta + kPi / 2.0)), d.norm()};
  };
  const auto& muscles = sampleMuscles();
  for (const char* side : {"_left", "_right"})
  {
    auto functions = [&](const std::string& id) {
      const FittedMuscle* m = findMuscle(muscles, id + side);
      EXPECT_NE(m, nullptr) << id << side;
      return m ? m->functions : std::vector<fem::Muscle>();
    };
    for (const auto& f : functions("zygomaticus_major"))
    {
      const Pull p = pull(f);
      EXPECT_GT(p.up, 10.0) << f.name << ": the smile lifts the mouth corner";
      EXPECT_GT(p.lateral, 10.0) << f.name << ": and draws it out";
    }
    for (const auto& f : functions("depressor_labii_inferioris"))
    {
      const Pull p = pull(f);
      EXPECT_LT(p.up, -5.0) << f.name << ": pulls the lower lip down";
      EXPECT_GT(p.lateral, -1.0) << f.name << ": and a little out";
    }
    for (const auto& f : functions("levator_labii_superioris"))
      EXPECT_GT(pull(f).up, 10.0) << f.name << ": lifts the upper lip";
    for (const auto& f : functions("levator_labii_superioris_alaeque_nasi"))
      EXPECT_GT(pull(f).up, 10.0) << f.name << ": lifts the ala and the lip";
    for (const auto& f : functions("risorius"))
    {
      const Pull p = pull(f);
      EXPECT_GT(p.lateral, 20.0) << f.name << ": draws the mouth corner out";
      EXPECT_LT(std::abs(p.up), 0.5 * p.lateral) << f.name << ": nearly horizontally";
    }
    for (const auto& f : functions("temporalis"))
      EXPECT_GT(pull(f).up, 20.0) << f.name << ": lifts the tissue over the ramus";
  }
  const FittedMuscle* corrugator = findMuscle(muscles, "corrugator_supercilii");
  ASSERT_NE(corrugator, nullptr);
  for (const auto& f : corrugator->functions)
  {
    const Pull p = pull(f);
    EXPECT_LT(p.lateral, -5.0) << f.name << ": the frown pulls the brow towards the midline";
    EXPECT_LT(p.up, 0.0) << f.name << ": and down";
  }

  // Orbicularis oris: at every point of the ring the pulls of the links that
  // attach there add up to a pull towards the middle of the ring (the mouth's
  // centre, behind the skin as the ring wraps round the teeth).
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> points; // point, net pull (N/mm^3 per unit weight)
  auto add = [&](const Eigen::Vector3d& at, const Eigen::Vector3d& force) {
    for (auto& [p, net] : points)
      if ((p - at).norm() < 1e-9)
      {
        net += force;
        return;
      }
    points.emplace_back(at, force);
  };
  for (const char* id : {"orbicularis_oris_upper", "orbicularis_oris_lower"})
  {
    const FittedMuscle* ring = findMuscle(muscles, id);
    ASSERT_NE(ring, nullptr);
    for (const auto& f : ring->functions)
    {
      EXPECT_GT(f.originRadius, 0.0) << f.name << ": both ends of a ring link are in the lip";
      EXPECT_EQ(f.originRadius, f.insertionRadius) << f.name << ": equal and opposite pulls";
      add(f.insertion, f.load * (f.origin - f.insertion));
      add(f.origin, f.load * (f.insertion - f.origin));
    }
  }
  EXPECT_EQ(points.size(), 12u); // 2 corners, 2 × 2 points per half lip, 2 midline points
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& [p, net] : points)
    centre += p / double(points.size());
  for (const auto& [p, net] : points)
  {
    const Eigen::Vector3d inward = (centre - p).normalized();
    EXPECT_GT(net.dot(inward), 0.3 * net.norm()) << "ring point " << p.transpose() << " is not pulled inwards";
  }
}

TEST(MuscleSetSample, ScaledLandmarksScaleTheAttachmentsExactly)
{
  // Heights from the nasion, angles from the nasion's θ (the offsets across
  // are arcs on the face's reference cylinder, whose radius is the skin's at
  // the nasion, which stays) and the sphere radii follow the landmarks
  // exactly; the depths follow the real tissue.
  const auto& face = test::sampleFace();
  const double k = 1.1;
  const auto big =
    fitMuscleSet(defaultSet(), scaledAboutNasion(face.landmarks.landmarks, k), face.maps.skin, face.maps.bone);
  const auto& base = sampleMuscles();
  ASSERT_EQ(base.size(), big.size());
  const double zn = face.landmarks.find("nasion")->z;
  const double front = face.landmarks.find("nasion")->theta;
  const auto& frame = face.maps.skin.frame();
  for (std::size_t m = 0; m < base.size(); ++m)
    for (std::size_t f = 0; f < base[m].functions.size(); ++f)
    {
      const fem::Muscle& a = base[m].functions[f];
      const fem::Muscle& b = big[m].functions[f];
      EXPECT_NEAR(frame.toCylindrical(b.insertion).z - zn, k * (frame.toCylindrical(a.insertion).z - zn), 1e-9);
      EXPECT_NEAR(frame.toCylindrical(b.origin).z - zn, k * (frame.toCylindrical(a.origin).z - zn), 1e-9);
      for (const auto& [pa, pb] : {std::pair{a.origin, b.origin}, std::pair{a.insertion, b.insertion}})
        EXPECT_NEAR(seg::CylindricalFrame::wrapTheta(frame.toCylindrical(pb).theta - front),
                    k * seg::CylindricalFrame::wrapTheta(frame.toCylindrical(pa).theta - front), 1e-9)
          << a.name << ": offsets across scale with the face too";
      EXPECT_NEAR(b.insertionRadius, k * a.insertionRadius, 1e-12);
      EXPECT_NEAR(b.load, a.load / (k * k), 1e-15);
    }
}

TEST(MuscleSetSample, ForcesAreOfTheOrderOfANewton)
{
  // Force on the insertion at activation 1: l |p_o − p_i| × the tissue volume
  // of the insertion sphere (read from the range maps, independently of the
  // mesh). Printed for the file's README. The loads of the file are for the
  // adult mean face (0.5 to 2 N a function); this face is 1.12 times as
  // big, so 1.12² times as strong. The set's load_scale (the calibration
  // of activation 1 against the face model's movement) is divided out.
  const auto& face = test::sampleFace();
  const double calibration = defaultSet().loadScale;
  std::printf("[ forces ] face size %.3f (nasion-subnasale / 53 mm)\n", faceSize(face.landmarks.landmarks));
  std::printf("[ forces ] %-48s %8s %6s %8s %8s\n", "function", "|po-pi|", "r_i", "V_in", "F (N)");
  for (const auto& m : sampleMuscles())
  {
    double total = 0.0;
    for (const auto& f : m.functions)
    {
      const double d = (f.origin - f.insertion).norm();
      const double v = tissueVolume(face.maps.skin, face.maps.bone, f.insertion, f.insertionRadius);
      const double force = f.load / calibration * d * v;
      std::printf("[ forces ] %-48s %8.1f %6.2f %8.0f %8.3f\n", f.name.c_str(), d, f.insertionRadius, v, force);
      EXPECT_GT(force, 0.15) << f.name;
      EXPECT_LT(force, 3.0) << f.name;
      total += force;
    }
    std::printf("[ forces ] %-48s %33.3f\n", (m.id + " total").c_str(), total);
  }
}

TEST(MuscleSetSample, EachMuscleMovesTheSkinAsTheAnatomySays)
{
  // End to end on the whole-face model (coarse, 8 mm): each fitted muscle
  // alone at activation 1, and the skin node over its insertion.
  const auto& face = test::sampleFace();
  const auto& skin = face.maps.skin;
  FaceModelOptions options;
  options.elementSize = 8.0;
  const FaceMesh model = meshFace(skin, face.maps.bone, face.landmarks.landmarks, options);
  fem::AssemblyOptions assembly;
  assembly.threads = 2;
  fem::LinearStaticAnalysis analysis(model.continuum.mesh, model.materials, model.continuum.constraints(), assembly);
  ASSERT_EQ(analysis.prepare(), fem::SolverStatus::Success) << analysis.message();
  const auto& muscles = sampleMuscles();
  std::vector<std::vector<fem::Muscle>> sets;
  for (const auto& m : muscles)
    sets.push_back(m.functions);
  const MuscleResponses responses(analysis, sets);
  const fem::Mesh& mesh = model.continuum.mesh;
  const seg::CylindricalFrame& frame = skin.frame();
  const double front = face.landmarks.find("nasion")->theta;

  struct Move
  {
    double up, lateral, size;
  };
  // The displacement of the mesh node nearest the skin over (θ, z) under the
  // activations, in the face's local axes there.
  auto move = [&](double theta, double z, const Eigen::VectorXd& activations) {
    const Eigen::Vector3d at = frame.toWorld(skin.sample(theta, z), theta, z);
    Eigen::Index node = 0;
    (mesh.nodes.colwise() - at).colwise().squaredNorm().minCoeff(&node);
    const Eigen::Vector3d d = responses.combined(activations).segment<3>(3 * node);
    const double side = seg::CylindricalFrame::wrapTheta(theta - front) > 0.0 ? 1.0 : -1.0;
    return Move{d.dot(frame.direction()), side * d.dot(frame.radialDirection(theta + kPi / 2.0)), d.norm()};
  };
  auto only = [&](std::initializer_list<const char*> ids) {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(muscles.size()));
    for (const char* id : ids)
      for (std::size_t k = 0; k < muscles.size(); ++k)
        if (muscles[k].id == id)
          a[Eigen::Index(k)] = 1.0;
    EXPECT_GT(a.sum(), 0.0);
    return a;
  };
  auto overInsertion = [&](const char* id, std::size_t function, std::initializer_list<const char*> active) {
    const FittedMuscle* m = findMuscle(muscles, id);
    EXPECT_NE(m, nullptr) << id;
    const AttachmentPlacement& p = m->placements.at(function).second;
    const Move mv = move(p.theta, p.z, only(active));
    std::printf("[ moves ] %-44s up %6.2f lateral %6.2f |d| %5.2f mm\n", m->functions.at(function).name.c_str(), mv.up,
                mv.lateral, mv.size);
    EXPECT_GT(mv.size, 0.05) << id << " barely moves the skin";
    return mv;
  };
  for (const std::string side : {"_left", "_right"})
  {
    const std::string zyg = "zygomaticus_major" + side, ris = "risorius" + side,
                      lls = "levator_labii_superioris" + side, llsan = "levator_labii_superioris_alaeque_nasi" + side,
                      dli = "depressor_labii_inferioris" + side, tem = "temporalis" + side;
    Move m = overInsertion(zyg.c_str(), 0, {zyg.c_str()});
    EXPECT_GT(m.up, 0.0) << zyg << ": smile lifts the corner";
    EXPECT_GT(m.lateral, 0.0) << zyg << ": and draws it out";
    EXPECT_GT(overInsertion(ris.c_str(), 0, {ris.c_str()}).lateral, 0.0) << ris;
    EXPECT_GT(overInsertion(lls.c_str(), 0, {lls.c_str()}).up, 0.0) << lls;
    EXPECT_GT(overInsertion(llsan.c_str(), 0, {llsan.c_str()}).up, 0.0) << llsan << ": the ala";
    EXPECT_LT(overInsertion(dli.c_str(), 0, {dli.c_str()}).up, 0.0) << dli;
    EXPECT_GT(overInsertion(tem.c_str(), 0, {tem.c_str()}).up, 0.0) << tem;
  }
  for (std::size_t brow : {0u, 1u})
    EXPECT_LT(overInsertion("corrugator_supercilii", brow, {"corrugator_supercilii"}).lateral, 0.0)
      << "the frown draws the brows together";
  // Both rings: the mouth corners move towards the midline.
  for (std::size_t corner : {0u, 1u})
  {
    const FittedMuscle* ring = findMuscle(muscles, "orbicularis_oris_upper");
    ASSERT_NE(ring, nullptr);
    const AttachmentPlacement& p = ring->placements.at(corner).first; // corner_left / corner_right origin: the corner
    const Move mv = move(p.theta, p.z, only({"orbicularis_oris_upper", "orbicularis_oris_lower"}));
    std::printf("[ moves ] orbicularis oris, corner %zu: up %6.2f lateral %6.2f |d| %5.2f mm\n", corner, mv.up,
                mv.lateral, mv.size);
    EXPECT_LT(mv.lateral, 0.0) << "the sphincter narrows the mouth";
  }
}
