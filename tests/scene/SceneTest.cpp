// Scene: ids, lookup by id and type, removal, observers.

#include <gtest/gtest.h>

#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

TEST(Scene, AssignsUniqueIdsPerType) {
  Scene scene;
  auto* v1 = scene.add<VolumeNode>();
  auto* v2 = scene.add<VolumeNode>();
  auto* p1 = scene.add<PlanNode>();
  EXPECT_EQ(v1->id(), "Volume1");
  EXPECT_EQ(v2->id(), "Volume2");
  EXPECT_EQ(p1->id(), "Plan1");
  EXPECT_EQ(v1->scene(), &scene);
  // A taken id is skipped; a given id is kept.
  auto named = std::make_unique<VolumeNode>();
  named->setId("Volume3");
  scene.addNode(std::move(named));
  EXPECT_EQ(scene.add<VolumeNode>()->id(), "Volume4");
  // Removing does not make the next id reuse an old one.
  scene.removeNode("Volume4");
  EXPECT_EQ(scene.add<VolumeNode>()->id(), "Volume5");
}

TEST(Scene, RejectsDuplicateIdsAndNullAndIdChangesInScene) {
  Scene scene;
  auto* v = scene.add<VolumeNode>();
  auto dup = std::make_unique<PlanNode>();
  dup->setId(v->id());
  EXPECT_THROW(scene.addNode(std::move(dup)), SceneError);
  EXPECT_THROW(scene.addNode(nullptr), SceneError);
  EXPECT_THROW(v->setId("Other"), SceneError);
  EXPECT_EQ(scene.size(), 1u);
}

TEST(Scene, FindsByIdTypeAndKeepsInsertionOrder) {
  Scene scene;
  auto* s = scene.add<SurfaceNode>();
  auto* v = scene.add<VolumeNode>();
  auto* s2 = scene.add<SurfaceNode>();
  EXPECT_EQ(scene.node("Volume1"), v);
  EXPECT_EQ(scene.node("Nope"), nullptr);
  EXPECT_EQ(scene.nodeAs<VolumeNode>("Volume1"), v);
  EXPECT_EQ(scene.nodeAs<PlanNode>("Volume1"), nullptr);  // wrong type
  EXPECT_EQ(scene.nodes(), (std::vector<Node*>{s, v, s2}));
  EXPECT_EQ(scene.nodesOfType(NodeType::Surface), (std::vector<Node*>{s, s2}));
  EXPECT_TRUE(scene.nodesOfType(NodeType::Plan).empty());
  EXPECT_TRUE(scene.removeNode("Surface1"));
  EXPECT_FALSE(scene.removeNode("Surface1"));
  EXPECT_EQ(scene.nodes(), (std::vector<Node*>{v, s2}));
  scene.clear();
  EXPECT_EQ(scene.size(), 0u);
  EXPECT_EQ(scene.node("Volume1"), nullptr);
}

TEST(Scene, ObserversSeeAddModifyRemove) {
  Scene scene;
  std::vector<std::pair<SceneEvent, std::string>> seen;
  const int tag = scene.addObserver([&](SceneEvent e, const Node& n) { seen.emplace_back(e, n.id()); });
  auto* p = scene.add<PlanNode>();
  p->setNotes("x");
  p->modified();
  scene.removeNode(p->id());
  const std::vector<std::pair<SceneEvent, std::string>> expected{{SceneEvent::NodeAdded, "Plan1"},
                                                                 {SceneEvent::NodeModified, "Plan1"},
                                                                 {SceneEvent::NodeModified, "Plan1"},
                                                                 {SceneEvent::NodeAboutToBeRemoved, "Plan1"}};
  EXPECT_EQ(seen, expected);
  scene.removeObserver(tag);
  scene.add<PlanNode>();
  EXPECT_EQ(seen.size(), expected.size());
}

TEST(Scene, NodeStillValidWhenAboutToBeRemoved) {
  Scene scene;
  scene.add<VolumeNode>()->setName("CT");
  std::string name;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAboutToBeRemoved) name = n.name();
  });
  scene.clear();
  EXPECT_EQ(name, "CT");
}

TEST(Scene, ObserversMayAddAndRemoveObserversWhileCalled) {
  Scene scene;
  int a = 0, b = 0, late = 0;
  int tagB = 0;
  int tagA = 0;
  tagA = scene.addObserver([&](SceneEvent, const Node&) {
    ++a;
    scene.removeObserver(tagA);  // remove itself
    scene.removeObserver(tagB);  // and one not yet called: it must not be called
    scene.addObserver([&](SceneEvent, const Node&) { ++late; });
  });
  tagB = scene.addObserver([&](SceneEvent, const Node&) { ++b; });
  scene.add<PlanNode>();
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 0);
  EXPECT_EQ(late, 0);  // added during the notification: from the next one on
  scene.add<PlanNode>();
  EXPECT_EQ(a, 1);
  EXPECT_EQ(late, 1);
}

TEST(Scene, ObserverRemovingTheNodeBeingAdded) {
  Scene scene;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAdded && n.type() == NodeType::Plan) scene.removeNode(n.id());
  });
  EXPECT_EQ(scene.add<PlanNode>(), nullptr);
  EXPECT_EQ(scene.size(), 0u);
}

TEST(Scene, NodeOutsideASceneNotifiesNobody) {
  PlanNode p;
  p.setNotes("free");  // must not crash
  EXPECT_EQ(p.scene(), nullptr);
}

}  // namespace
}  // namespace caps
