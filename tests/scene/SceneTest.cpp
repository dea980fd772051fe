// Scene: ids, lookup by id and type, removal, observers.

#include <gtest/gtest.h>

#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

TEST(Scene, AssignsUniqueIdsPerType)
{
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

TEST(Scene, RejectsDuplicateIdsAndNullAndIdChangesInScene)
{
  Scene scene;
  auto* v = scene.add<VolumeNode>();
  auto dup = std::make_unique<PlanNode>();
  dup->setId(v->id());
  EXPECT_THROW(scene.addNode(std::move(dup)), SceneError);
  EXPECT_THROW(scene.addNode(nullptr), SceneError);
  EXPECT_THROW(v->setId("Other"), SceneError);
  EXPECT_EQ(scene.size(), 1u);
}

TEST(Scene, FindsByIdTypeAndKeepsInsertionOrder)
{
  Scene scene;
  auto* s = scene.add<SurfaceNode>();
  auto* v = scene.add<VolumeNode>();
  auto* s2 = scene.add<SurfaceNode>();
  EXPECT_EQ(scene.node("Volume1"), v);
  EXPECT_EQ(scene.node("Nope"), nullptr);
  EXPECT_EQ(scene.nodeAs<VolumeNode>("Volume1"), v);
  EXPECT_EQ(scene.nodeAs<PlanNode>("Volume1"), nullptr); // wrong type
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

TEST(Scene, ObserversSeeAddModifyRemove)
{
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

TEST(Scene, NodeStillValidWhenAboutToBeRemoved)
{
  Scene scene;
  scene.add<VolumeNode>()->setName("CT");
  std::string name;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAboutToBeRemoved)
      name = n.name();
  });
  scene.clear();
  EXPECT_EQ(name, "CT");
}

TEST(Scene, ObserversMayAddAndRemoveObserversWhileCalled)
{
  Scene scene;
  int a = 0, b = 0, late = 0;
  int tagB = 0;
  int tagA = 0;
  tagA = scene.addObserver([&](SceneEvent, const Node&) {
    ++a;
    scene.removeObserver(tagA); // remove itself
    scene.removeObserver(tagB); // and one not yet called: it must not be called
    scene.addObserver([&](SceneEvent, const Node&) { ++late; });
  });
  tagB = scene.addObserver([&](SceneEvent, const Node&) { ++b; });
  scene.add<PlanNode>();
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 0);
  EXPECT_EQ(late, 0); // added during the notification: from the next one on
  scene.add<PlanNode>();
  EXPECT_EQ(a, 1);
  EXPECT_EQ(late, 1);
}

TEST(Scene, ObserverRemovingTheNodeBeingAdded)
{
  Scene scene;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAdded && n.type() == NodeType::Plan)
      scene.removeNode(n.id());
  });
  EXPECT_EQ(scene.add<PlanNode>(), nullptr);
  EXPECT_EQ(scene.size(), 0u);
}

// The first observer removes (destroys) the node it is told about: the next
// observers must not be called with the dead node, and removeNode must not
// read the id of the dead node it was given by reference.
TEST(Scene, ObserverRemovingTheNodeItIsToldAboutStopsTheNotification)
{
  Scene scene;
  bool removing = false;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e != SceneEvent::NodeAdded && !removing)
    {
      removing = true;
      scene.removeNode(n.id());
    }
  });
  std::vector<std::pair<SceneEvent, std::string>> seen;
  scene.addObserver([&](SceneEvent e, const Node& n) { seen.emplace_back(e, n.id() + "/" + n.name()); });

  auto* p = scene.add<PlanNode>();
  p->setName("a"); // NodeModified: the first observer removes Plan1
  EXPECT_EQ(scene.size(), 0u);
  // Not NodeModified: the node was gone by the time the second observer's turn came.
  const std::vector<std::pair<SceneEvent, std::string>> expected{{SceneEvent::NodeAdded, "Plan1/"},
                                                                 {SceneEvent::NodeAboutToBeRemoved, "Plan1/a"}};
  EXPECT_EQ(seen, expected);
}

TEST(Scene, ObserverRemovingTheNodeFromItsOwnRemoval)
{
  Scene scene;
  scene.add<PlanNode>()->setName("a");
  bool removing = false;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAboutToBeRemoved && !removing)
    {
      removing = true;
      scene.removeNode(n.id()); // nested: the inner call tells everybody and destroys it
    }
  });
  int told = 0;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAboutToBeRemoved && n.name() == "a")
      ++told;
  });
  const Node* p = scene.node("Plan1");
  EXPECT_TRUE(scene.removeNode(p->id())); // a reference into the node that dies mid-call
  EXPECT_EQ(told, 1);
  EXPECT_EQ(scene.size(), 0u);
  EXPECT_EQ(scene.node("Plan1"), nullptr);
}

TEST(Scene, ReplaceAllInstallsEverythingThenNotifies)
{
  Scene scene;
  scene.add<VolumeNode>()->setName("old CT");
  scene.add<PlanNode>();
  std::vector<std::pair<SceneEvent, std::string>> seen;
  std::size_t sizeWhenFirstTold = 0;
  scene.addObserver([&](SceneEvent e, const Node& n) {
    if (seen.empty())
      sizeWhenFirstTold = scene.size();
    seen.emplace_back(e, n.id() + "/" + n.name());
    // An observer adding a node while the new ones are announced.
    if (e == SceneEvent::NodeAdded && n.id() == "Volume1")
      scene.add<PlanNode>()->setName("from observer");
  });
  std::vector<std::unique_ptr<Node>> fresh;
  fresh.push_back(std::make_unique<VolumeNode>());
  fresh.back()->setId("Volume1"); // the same id as an old node
  fresh.back()->setName("new CT");
  fresh.push_back(std::make_unique<PlanNode>());
  fresh.back()->setId("Plan1");
  fresh.push_back(std::make_unique<SurfaceNode>()); // no id: gets one
  scene.replaceAll(std::move(fresh));

  EXPECT_EQ(sizeWhenFirstTold, 3u);
  ASSERT_EQ(scene.size(), 4u);
  EXPECT_EQ(scene.node("Volume1")->name(), "new CT");
  EXPECT_EQ(scene.node("Plan1")->scene(), &scene);
  EXPECT_EQ(scene.nodes()[2]->id(), "Surface1");
  EXPECT_EQ(scene.nodes()[3]->name(), "from observer");
  EXPECT_EQ(scene.nodes()[3]->id(), "Plan2");
  const std::vector<std::pair<SceneEvent, std::string>> expected{{SceneEvent::NodeAboutToBeRemoved, "Plan1/"},
                                                                 {SceneEvent::NodeAboutToBeRemoved, "Volume1/old CT"},
                                                                 {SceneEvent::NodeAdded, "Volume1/new CT"},
                                                                 {SceneEvent::NodeAdded, "Plan2/"},
                                                                 {SceneEvent::NodeModified, "Plan2/from observer"},
                                                                 {SceneEvent::NodeAdded, "Plan1/"},
                                                                 {SceneEvent::NodeAdded, "Surface1/"}};
  EXPECT_EQ(seen, expected);
}

TEST(Scene, ReplaceAllRejectsBadNodesAndLeavesTheSceneUnchanged)
{
  Scene scene;
  auto* v = scene.add<VolumeNode>();
  std::vector<std::unique_ptr<Node>> dup;
  dup.push_back(std::make_unique<PlanNode>());
  dup.back()->setId("P");
  dup.push_back(std::make_unique<SurfaceNode>());
  dup.back()->setId("P");
  EXPECT_THROW(scene.replaceAll(std::move(dup)), SceneError);
  std::vector<std::unique_ptr<Node>> withNull(1);
  EXPECT_THROW(scene.replaceAll(std::move(withNull)), SceneError);
  EXPECT_EQ(scene.nodes(), std::vector<Node*>{v});
  scene.replaceAll({});
  EXPECT_EQ(scene.size(), 0u);
}

TEST(Scene, NodeOutsideASceneNotifiesNobody)
{
  PlanNode p;
  p.setNotes("free"); // must not crash
  EXPECT_EQ(p.scene(), nullptr);
}

} // namespace
} // namespace caps
