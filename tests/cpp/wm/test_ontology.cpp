#include <gtest/gtest.h>

#include "skillbus/wm/model.hpp"
#include "wm_test_util.hpp"

using namespace skillbus::wm;
using test::ontology;

TEST(Ontology, SubclassesIncludeTheClassAndEverythingBelow) {
  const auto& subs = ontology().subclasses("skiros:Product");
  EXPECT_TRUE(subs.count("skiros:Product"));
  EXPECT_TRUE(subs.count("skiros:Cube"));
  EXPECT_TRUE(subs.count("skiros:Starter"));
  EXPECT_FALSE(subs.count("skiros:Table"));
  EXPECT_TRUE(ontology().is_subclass("skiros:Scene", "skiros:PhysicalObject"));  // two levels up
  EXPECT_TRUE(ontology().subclasses("skiros:NoSuchThing").empty());
}

TEST(Ontology, SubpropertiesAndRanges) {
  EXPECT_TRUE(ontology().is_subproperty("skiros:contain", "skiros:spatiallyRelated"));
  EXPECT_FALSE(ontology().is_subproperty("skiros:hasA", "skiros:spatiallyRelated"));
  EXPECT_EQ(ontology().data_range("skiros:PositionX"), "float");
  EXPECT_EQ(ontology().data_range("skiros:PublishTf"), "bool");
  EXPECT_EQ(ontology().data_range("skiros:Unknown"), "");
}

TEST(Ontology, AbstractRelationsFromRestrictionsFollowBothHierarchies) {
  EXPECT_TRUE(ontology().may_relate("skiros:Location", "skiros:contain", "skiros:Product"));
  EXPECT_TRUE(ontology().may_relate("skiros:Table", "skiros:contain", "skiros:Cube"));   // subclasses
  EXPECT_TRUE(ontology().may_relate("skiros:Gripper", "skiros:contain", "skiros:Cube"));
  EXPECT_TRUE(ontology().may_relate("skiros:Table", "skiros:spatiallyRelated", "skiros:Cube"));  // superproperty
  EXPECT_FALSE(ontology().may_relate("skiros:Cube", "skiros:contain", "skiros:Table"));
  EXPECT_TRUE(ontology().may_relate("skiros:Robot", "skiros:hasA", "skiros:Gripper"));
  EXPECT_FALSE(ontology().may_relate("skiros:Robot", "skiros:contain", "skiros:Gripper"));
}

TEST(Ontology, PlainClassLevelTriplesAreAbstractRelationsToo) {
  Ontology o = ontology();
  Prefixes p;
  o.load_turtle(R"(@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
                   @prefix owl: <http://www.w3.org/2002/07/owl#> .
                   skiros:Shelf a owl:Class . skiros:Shelf skiros:at skiros:Table .)",
                p, "extra");
  EXPECT_TRUE(o.may_relate("skiros:Shelf", "skiros:at", "skiros:Table"));
  EXPECT_FALSE(o.may_relate("skiros:Table", "skiros:at", "skiros:Shelf"));
}

TEST(Ontology, MalformedTurtleNamesTheLine) {
  Ontology o;
  Prefixes p;
  try {
    o.load_turtle("@prefix x: <http://x#> .\nx:a x:b \"unterminated .\n", p, "broken.ttl");
    FAIL() << "expected WmError";
  } catch (const WmError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("broken.ttl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("line"), std::string::npos) << msg;
  }
}
