#include <gtest/gtest.h>

#include <algorithm>

#include "skillbus/wm/rdf.hpp"
#include "skillbus/wm/scene.hpp"
#include "wm_test_util.hpp"

using namespace skillbus::wm;
using namespace skillbus::wm::test;

namespace {

// In the form SkiROS2 writes its scenes (owl/planning_scene.turtle of skiros2_examples).
const char* kSkirosScene = R"(@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
@prefix xsd: <http://www.w3.org/2001/XMLSchema#> .

skiros:Pick a owl:class ;
    rdfs:subClassOf skiros:Skill .

skiros:Scene-0 a skiros:Scene,
        owl:NamedIndividual ;
    rdfs:label "" ;
    skiros:FrameId "map"^^xsd:string ;
    skiros:OrientationW "1.0"^^xsd:float ;
    skiros:PositionX "0.0"^^xsd:float ;
    skiros:contain skiros:LargeBox-51 .

skiros:LargeBox-51 a skiros:LargeBox,
        owl:NamedIndividual ;
    rdfs:label "start_box" ;
    skiros:FrameId "skiros:LargeBox-51"^^xsd:string ;
    skiros:PublishTf true ;
    skiros:contain skiros:Starter-52 ;
    skiros:hasTemplate skiros:large_box_test_starter .

skiros:Starter-52 a skiros:Starter,
        owl:NamedIndividual ;
    rdfs:label "starter1" ;
    skiros:Weight "3.0"^^xsd:float ;
    skiros:Count "7"^^xsd:int .
)";

}  // namespace

TEST(Scene, ReadsTheSkirosFormAndKeepsWhatIsNoElement) {
  Ontology onto = ontology();
  Prefixes px;
  Scene s = read_scene(kSkirosScene, onto, px, "planning_scene.turtle");
  ASSERT_EQ(s.elements.size(), 3u);
  const Element& box = s.elements[0];
  EXPECT_EQ(box.id, "skiros:LargeBox-51");
  EXPECT_EQ(box.type, "skiros:LargeBox");
  EXPECT_EQ(box.label, "start_box");
  EXPECT_EQ(box.properties.at("skiros:PublishTf")[0], Value(true));
  EXPECT_EQ(s.elements[2].properties.at("skiros:Count")[0], Value(int64_t{7}));
  EXPECT_EQ(s.elements[2].properties.at("skiros:Weight")[0], Value(3.0));
  ASSERT_EQ(s.relations.size(), 2u);
  EXPECT_TRUE(s.notes.empty());
  // hasTemplate points at no individual of the scene: kept aside, saved back with it
  EXPECT_TRUE(std::any_of(s.extra.begin(), s.extra.end(), [](const Triple& t) {
    return t.p.value == "http://rvmi.aau.dk/ontologies/skiros.owl#hasTemplate" &&
           t.o.value == "http://rvmi.aau.dk/ontologies/skiros.owl#large_box_test_starter";
  }));
  EXPECT_TRUE(onto.is_subclass("skiros:Pick", "skiros:Skill"));  // axioms in the scene reach the ontology
}

TEST(Scene, SaveThenLoadGivesTheSameWorld) {
  Ontology onto = ontology();
  Prefixes px;
  Scene s = read_scene(kSkirosScene, onto, px, "scene");
  WorldStore a(onto);
  a.reset(s.elements, s.relations, 1, 1);
  const std::string text = write_scene(a, px, s.extra);
  Prefixes px2;
  Scene s2 = read_scene(text, onto, px2, "saved");
  WorldStore b(onto);
  b.reset(s2.elements, s2.relations, 1, 1);
  EXPECT_EQ(a.elements(), b.elements());
  EXPECT_EQ(a.all_relations(), b.all_relations());
  EXPECT_TRUE(s2.notes.empty());
  EXPECT_EQ(s2.extra.size(), s.extra.size());  // the class axiom and the template relation came back
  EXPECT_EQ(write_scene(b, px2, s2.extra), text);  // and saving is stable
}

TEST(Scene, IdsAreWrittenAsPrefixedNames) {
  // serd alone would write <http://rvmi.aau.dk/ontologies/skiros.owl#Cube-1>
  Ontology onto = ontology();
  WorldStore a(onto);
  a.apply({add(element("", "skiros:Cube", "c", {{"skiros:PositionX", {0.5}}}))});
  const std::string text = write_scene(a, Prefixes());
  EXPECT_NE(text.find("skiros:Cube-1\n\ta skiros:Cube"), std::string::npos) << text;
  auto count = [&](const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<http"), count("@prefix")) << text;  // full IRIs only in the @prefix lines
}

TEST(Scene, ExactFloatsSurviveTheRoundTrip) {
  Ontology onto = ontology();
  WorldStore a(onto);
  a.apply({add(element("", "skiros:Cube", "c", {{"skiros:PositionX", {0.1 + 0.2}}, {"skiros:Size", {1e-300}}}))});
  Prefixes px;
  Scene s = read_scene(write_scene(a, px), onto, px, "saved");
  EXPECT_EQ(s.elements[0].properties, a.get("skiros:Cube-1")->properties);
}

TEST(Turtle, ALiteralNotItsDatatypesTokenIsWrittenQuotedAndReadsBackAsItWas) {
  // serd writes xsd:integer, xsd:decimal and xsd:boolean literals bare: one whose text is
  // no such token would add a triple, not read, or change its type (saved scenes, the
  // journal's scene files and the ontology RPC are this Turtle).
  const std::string xsd = kXsd;
  auto lit = [](const std::string& v, const std::string& dt) { return Term{Term::Literal, v, dt, ""}; };
  const Term s{Term::Iri, "http://rvmi.aau.dk/ontologies/skiros.owl#Note-1", "", ""};
  const Term p{Term::Iri, "http://rvmi.aau.dk/ontologies/skiros.owl#value", "", ""};
  const std::vector<Term> objects = {
      lit("1 . <http://x/a> <http://x/b> <http://x/c>", xsd + "integer"), lit("abc", xsd + "integer"),
      lit("1.0", xsd + "integer"), lit("1", xsd + "boolean"), lit("1.5e3", xsd + "decimal"), lit("", xsd + "integer"),
      lit("42", xsd + "integer"), lit("-1.5", xsd + "decimal"), lit("true", xsd + "boolean")};
  std::vector<Triple> triples;
  for (const Term& o : objects) triples.push_back({s, p, o});
  Prefixes px;
  const std::string text = write_turtle(triples, px);
  Prefixes read_px;
  const std::vector<Triple> back = parse_turtle(text, read_px, "written");
  ASSERT_EQ(back.size(), triples.size()) << text;
  for (size_t i = 0; i < triples.size(); ++i) {
    EXPECT_EQ(back[i].o.value, triples[i].o.value) << text;
    EXPECT_EQ(back[i].o.datatype, triples[i].o.datatype) << text;
  }
  EXPECT_EQ(text.find("\"42\""), std::string::npos) << "a datatype's own token is still written bare: " << text;
  EXPECT_EQ(text.find("\"true\""), std::string::npos) << text;
}

TEST(Scene, BadValuesAreNamed) {
  Ontology onto = ontology();
  Prefixes px;
  const std::string bad = std::string(kSkirosScene).replace(std::string(kSkirosScene).find("\"3.0\""), 5, "\"heavy\"");
  try {
    read_scene(bad, onto, px, "bad.turtle");
    FAIL();
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.turtle, skiros:Starter-52 skiros:Weight: 'heavy' is not a number"),
              std::string::npos)
        << e.what();
  }
}
