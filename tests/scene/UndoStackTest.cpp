// Undo/redo of plan edits through ScopedEdit mementos.

#include <gtest/gtest.h>

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"
#include "scene/ScopedEdit.h"
#include "scene/SurfaceNode.h"

namespace caps {
namespace {

struct UndoFixture : ::testing::Test
{
  Scene scene;
  PlanNode* plan = nullptr;
  void SetUp() override
  {
    plan = scene.add<PlanNode>();
    plan->setCutPath({{0, 0}, {0.1, 0.1}, {0.2, 0.0}, {0.3, -0.1}});
  }
  void move(std::size_t i, double x)
  {
    ScopedEdit edit(scene, plan->id(), "Move point " + std::to_string(i));
    plan->setCutPoint(i, {x, x});
  }
};

TEST_F(UndoFixture, UndoRedoRestoresStateAndNotifies)
{
  int modified = 0;
  scene.addObserver([&](SceneEvent e, const Node&) { modified += e == SceneEvent::NodeModified; });
  EXPECT_FALSE(scene.undoStack().canUndo());
  move(3, 0.9);
  EXPECT_TRUE(scene.undoStack().canUndo());
  EXPECT_FALSE(scene.undoStack().canRedo());
  EXPECT_EQ(scene.undoStack().undoLabel(), "Move point 3");
  modified = 0;
  EXPECT_TRUE(scene.undoStack().undo());
  EXPECT_EQ(modified, 1);
  EXPECT_EQ(plan->cutPath()[3], Eigen::Vector2d(0.3, -0.1));
  EXPECT_EQ(scene.undoStack().redoLabel(), "Move point 3");
  EXPECT_EQ(scene.undoStack().undoLabel(), "");
  EXPECT_FALSE(scene.undoStack().undo());
  EXPECT_TRUE(scene.undoStack().redo());
  EXPECT_EQ(modified, 2);
  EXPECT_EQ(plan->cutPath()[3], Eigen::Vector2d(0.9, 0.9));
  EXPECT_FALSE(scene.undoStack().redo());
}

TEST_F(UndoFixture, NoEntryWhenNothingChanged)
{
  {
    ScopedEdit edit(scene, plan->id(), "Nothing");
  }
  {
    ScopedEdit edit(scene, plan->id(), "Same value");
    plan->setCutPoint(0, {0, 0});
  }
  EXPECT_FALSE(scene.undoStack().canUndo());
}

TEST_F(UndoFixture, SeveralEditsUndoInOrder)
{
  move(0, 0.5);
  {
    ScopedEdit edit(scene, plan->id(), "Set procedure");
    plan->setProcedure("z-plasty");
    plan->setParameter("angle", 1.0);
  }
  move(1, 0.7);
  EXPECT_EQ(scene.undoStack().size(), 3u);
  scene.undoStack().undo();
  scene.undoStack().undo();
  EXPECT_EQ(plan->procedure(), "");
  EXPECT_TRUE(plan->parameters().empty());
  EXPECT_EQ(plan->cutPath()[0], Eigen::Vector2d(0.5, 0.5));
  EXPECT_EQ(scene.undoStack().redoLabel(), "Set procedure");
}

TEST_F(UndoFixture, NewEditClearsRedoTail)
{
  move(0, 0.5);
  move(1, 0.6);
  scene.undoStack().undo();
  EXPECT_TRUE(scene.undoStack().canRedo());
  move(2, 0.8);
  EXPECT_FALSE(scene.undoStack().canRedo());
  EXPECT_EQ(scene.undoStack().size(), 2u);
  EXPECT_EQ(scene.undoStack().undoLabel(), "Move point 2");
}

TEST_F(UndoFixture, DepthLimitDropsOldest)
{
  EXPECT_EQ(scene.undoStack().depthLimit(), 100u);
  for (int i = 0; i < 130; ++i)
    move(0, 0.001 * (i + 1));
  EXPECT_EQ(scene.undoStack().size(), 100u);
  int undone = 0;
  while (scene.undoStack().undo())
    ++undone;
  EXPECT_EQ(undone, 100);
  EXPECT_DOUBLE_EQ(plan->cutPath()[0].x(), 0.030); // state after edit 30
}

TEST_F(UndoFixture, RemovingANodeDropsItsEntries)
{
  auto* other = scene.add<PlanNode>();
  move(0, 0.5);
  {
    ScopedEdit edit(scene, other->id(), "Notes");
    other->setNotes("keep");
  }
  move(1, 0.6);
  scene.undoStack().undo(); // undo "Move point 1"
  ASSERT_TRUE(scene.removeNode(plan->id()));
  EXPECT_EQ(scene.undoStack().size(), 1u);
  EXPECT_EQ(scene.undoStack().undoLabel(), "Notes");
  EXPECT_FALSE(scene.undoStack().canRedo());
  scene.undoStack().undo();
  EXPECT_EQ(other->notes(), "");
}

TEST_F(UndoFixture, EditOfAMissingNodeThrows)
{
  EXPECT_THROW(ScopedEdit(scene, "Plan99", "x"), SceneError);
}

TEST_F(UndoFixture, NodeRemovedDuringEditIsNotRecorded)
{
  {
    ScopedEdit edit(scene, plan->id(), "Edit then delete");
    plan->setNotes("gone");
    scene.removeNode(plan->id());
  }
  EXPECT_FALSE(scene.undoStack().canUndo());
}

TEST_F(UndoFixture, AnAdditionIsUndoneByTakingTheNodeOutAndRedoneWithItsIdAndState)
{
  std::vector<std::pair<SceneEvent, NodeId>> events;
  scene.addObserver([&](SceneEvent e, const Node& n) { events.emplace_back(e, n.id()); });
  auto* added = scene.add<PlanNode>();
  added->setName("Added plan");
  added->setCutPath({{0, 0}, {0.5, 0.5}});
  const NodeId id = added->id();
  scene.undoStack().pushAddition(*added, "Add plan");
  move(1, 0.7); // an edit of another node after it
  ASSERT_EQ(scene.size(), 2u);

  EXPECT_TRUE(scene.undoStack().undo()); // the move
  events.clear();
  EXPECT_EQ(scene.undoStack().undoLabel(), "Add plan");
  EXPECT_TRUE(scene.undoStack().undo()); // the addition
  EXPECT_EQ(scene.node(id), nullptr);
  EXPECT_EQ(scene.size(), 1u);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], std::make_pair(SceneEvent::NodeAboutToBeRemoved, id));
  EXPECT_EQ(scene.undoStack().redoLabel(), "Add plan");

  events.clear();
  EXPECT_TRUE(scene.undoStack().redo());
  auto* back = scene.nodeAs<PlanNode>(id);
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->name(), "Added plan");
  ASSERT_EQ(back->cutPath().size(), 2u);
  EXPECT_EQ(back->cutPath()[1], Eigen::Vector2d(0.5, 0.5));
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events[0], std::make_pair(SceneEvent::NodeAdded, id));
  EXPECT_TRUE(scene.undoStack().redo()); // the move, still there after the addition
  EXPECT_EQ(plan->cutPath()[1], Eigen::Vector2d(0.7, 0.7));

  // Removing the node by hand drops its entries, the addition with them.
  scene.removeNode(id);
  EXPECT_EQ(scene.undoStack().size(), 1u);
  EXPECT_EQ(scene.undoStack().undoLabel(), "Move point 1");
}

TEST_F(UndoFixture, AnAdditionThatCouldNotBePutBackIsRefused)
{
  auto* surface = scene.add<SurfaceNode>();
  surface->setPolyData(vtkSmartPointer<vtkPolyData>::New()); // bulk data: a mesh
  EXPECT_THROW(scene.undoStack().pushAddition(*surface, "Add surface"), SceneError);
  Scene other;
  auto* elsewhere = other.add<PlanNode>();
  EXPECT_THROW(scene.undoStack().pushAddition(*elsewhere, "Add plan"), SceneError);
  EXPECT_FALSE(scene.undoStack().canUndo());
}

} // namespace
} // namespace caps
