#include <gtest/gtest.h>

#include "wm_test_util.hpp"

using namespace skillbus::wm;
using namespace skillbus::wm::test;

namespace {

std::vector<std::string> ids(const std::vector<const Element*>& es) {
  std::vector<std::string> out;
  for (auto* e : es) out.push_back(e->id);
  return out;
}

struct World : ::testing::Test {
  WorldStore store{ontology()};
  void SetUp() override {
    store.apply({add(element("", "skiros:Table", "table")), add(element("", "skiros:Cube", "red", {{"skiros:Size", {0.05}}})),
                 add(element("", "skiros:Cube", "blue")), add(element("", "skiros:Starter", "starter")),
                 relate("skiros:Table-1", "skiros:contain", "skiros:Cube-2")});
  }
};

}  // namespace

TEST_F(World, AddAssignsReadableIdsAndCountsVersions) {
  EXPECT_EQ(store.version(), 1);
  ASSERT_NE(store.get("skiros:Cube-2"), nullptr);
  EXPECT_EQ(store.get("skiros:Cube-2")->label, "red");
  auto r = store.apply({add(element("", "skiros:Cube", "green"))});
  EXPECT_EQ(r.ids, std::vector<std::string>{"skiros:Cube-5"});
  EXPECT_EQ(r.version, 2);
}

TEST_F(World, QueryByTypeIncludesSubclassesUnlessExact) {
  Query q;
  q.type = "skiros:Product";
  EXPECT_EQ(ids(store.query(q)), (std::vector<std::string>{"skiros:Cube-2", "skiros:Cube-3", "skiros:Starter-4"}));
  q.type = "skiros:Cube";
  q.exact_type = true;
  EXPECT_EQ(ids(store.query(q)).size(), 2u);
  q = Query{};
  q.type = "skiros:Product";
  q.exact_type = true;
  EXPECT_TRUE(store.query(q).empty());
}

TEST_F(World, QueryByLabelPropertyAndRelation) {
  Query q;
  q.label = "blue";
  EXPECT_EQ(ids(store.query(q)), std::vector<std::string>{"skiros:Cube-3"});
  q = Query{};
  q.properties["skiros:Size"] = {0.05};
  EXPECT_EQ(ids(store.query(q)), std::vector<std::string>{"skiros:Cube-2"});
  q = Query{};
  q.type = "skiros:Cube";
  q.relations.push_back(Relation{"skiros:Table-1", "skiros:spatiallyRelated", ""});  // via the subproperty contain
  EXPECT_EQ(ids(store.query(q)), std::vector<std::string>{"skiros:Cube-2"});
  q.relations = {Relation{"*", "skiros:contain", ""}};
  EXPECT_EQ(ids(store.query(q)), std::vector<std::string>{"skiros:Cube-2"});
}

TEST_F(World, TransactionsAreAllOrNothing) {
  std::map<std::string, Element> before;
  for (const auto& [id, e] : store.elements()) before.emplace(id, e);
  const auto next = store.next_id();
  try {
    store.apply({add(element("", "skiros:Cube", "ok")), relate("skiros:Table-1", "skiros:contain", "skiros:Nope-9")});
    FAIL() << "expected WmError";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("operation 2: relation (skiros:Table-1 skiros:contain skiros:Nope-9): no element skiros:Nope-9"),
              std::string::npos)
        << e.what();
  }
  std::map<std::string, Element> after;
  for (const auto& [id, e] : store.elements()) after.emplace(id, e);
  EXPECT_EQ(after, before);
  EXPECT_EQ(store.version(), 1);
  EXPECT_EQ(store.next_id(), next);
}

TEST_F(World, VersionConflict) {
  EXPECT_THROW(store.apply({add(element("", "skiros:Cube"))}, 0), WmError);
  EXPECT_NO_THROW(store.apply({add(element("", "skiros:Cube"))}, 1));
}

TEST_F(World, BadInputIsNamed) {
  auto error_of = [&](std::vector<Op> ops) {
    try {
      store.apply(ops);
    } catch (const WmError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of({add(element("", "skiros:Unicorn"))}).find("unknown type 'skiros:Unicorn'"), std::string::npos);
  EXPECT_NE(error_of({add(element("", "skiros:Cube", "", {{"skiros:PositionX", {std::string("left")}}}))})
                .find("property skiros:PositionX of skiros:Cube-5 must be float, got string"),
            std::string::npos);
  EXPECT_NE(error_of({Op{Op::UpdateElement, element("skiros:Cube-99", "skiros:Cube"), {}}}).find("no element skiros:Cube-99"),
            std::string::npos);
  EXPECT_NE(error_of({relate("skiros:Table-1", "skiros:likes", "skiros:Cube-3")}).find("unknown relation type skiros:likes"),
            std::string::npos);
  EXPECT_NE(error_of({add(element("skiros:Cube-2", "skiros:Cube"))}).find("exists already"), std::string::npos);
  EXPECT_NE(error_of({}).find("at least one operation"), std::string::npos);
  // A NUL in any string: it could never be sent again (LCM writes strings up to a NUL).
  EXPECT_NE(error_of({add(element("", "skiros:Cube", std::string("a\0b", 3)))}).find("a NUL character"),
            std::string::npos);
  EXPECT_NE(error_of({add(element("", "skiros:Cube", "", {{"skiros:Color", {std::string("r\0d", 3)}}}))})
                .find("a NUL character"),
            std::string::npos);
  EXPECT_EQ(store.version(), 1);
}

TEST_F(World, RemoveTakesItsRelationsAlong) {
  auto r = store.apply({Op{Op::RemoveElement, element("skiros:Cube-2", ""), {}}});
  EXPECT_EQ(store.get("skiros:Cube-2"), nullptr);
  EXPECT_TRUE(store.relations("", "", "skiros:Cube-2").empty());
  EXPECT_EQ(r.effect.size(), 2u);  // the relation, then the element
}

TEST_F(World, UpdateReplacesPropertiesAndUndoRestores) {
  store.apply({Op{Op::UpdateElement, element("skiros:Cube-2", "skiros:Cube", "red", {{"skiros:Size", {0.1}}}), {}}});
  EXPECT_EQ(std::get<double>(store.get("skiros:Cube-2")->properties.at("skiros:Size")[0]), 0.1);
  store.undo_last();
  EXPECT_EQ(std::get<double>(store.get("skiros:Cube-2")->properties.at("skiros:Size")[0]), 0.05);
  EXPECT_EQ(store.version(), 1);
}

// An editor's compare-and-set: the element as it was read goes with the edit, and the
// whole transaction is refused, naming what changed, when it is no longer so.
TEST_F(World, ExpectElementRefusesAnEditOfAStaleRead) {
  const Element read = *store.get("skiros:Cube-2");
  Element edited = read;
  edited.label = "crimson";
  const Op expect{Op::ExpectElement, read, {}};
  EXPECT_NO_THROW(store.apply({expect, Op{Op::UpdateElement, edited, {}}}));
  EXPECT_EQ(store.get("skiros:Cube-2")->label, "crimson");
  EXPECT_EQ(store.version(), 2);

  // Someone else changes the size; an edit of the old read changes nothing.
  Element bigger = *store.get("skiros:Cube-2");
  bigger.properties["skiros:Size"] = {0.2};
  store.apply({Op{Op::UpdateElement, bigger, {}}});
  Element again = read;
  again.label = "scarlet";
  try {
    store.apply({Op{Op::ExpectElement, edited, {}}, Op{Op::UpdateElement, again, {}}});
    FAIL() << "a stale edit was applied";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("skiros:Cube-2 changed since it was read (skiros:Size)"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(store.get("skiros:Cube-2")->label, "crimson");
  EXPECT_EQ(store.version(), 3);

  store.apply({Op{Op::RemoveElement, element("skiros:Cube-3", ""), {}}});
  try {
    store.apply({Op{Op::ExpectElement, element("skiros:Cube-3", "skiros:Cube", "blue"), {}}});
    FAIL() << "an element removed since it was read was expected";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("skiros:Cube-3 was removed since it was read"), std::string::npos) << e.what();
  }
}
