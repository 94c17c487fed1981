// Ontologies in RDF/XML (as SkiROS2's owl/ files are written), read through Raptor into
// the same ontology as Turtle; malformed XML named with its line; nothing outside the text
// read (no external entities); containment kept a tree by every write; every unknown
// type of a scene named at once.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "skillbus/wm/model.hpp"
#include "skillbus/wm/ontology_files.hpp"
#include "skillbus/wm/scene.hpp"
#include "wm_test_util.hpp"

using namespace skillbus::wm;

namespace {

// A small ontology as Protégé writes it: entities declared in a DOCTYPE, an xml:base, a
// class hierarchy, an object property with a subproperty, a data property with a range,
// an owl:Restriction and an import.
const char* kOwl = R"(<?xml version="1.0"?>
<!DOCTYPE rdf:RDF [
    <!ENTITY owl "http://www.w3.org/2002/07/owl#" >
    <!ENTITY xsd "http://www.w3.org/2001/XMLSchema#" >
    <!ENTITY rdfs "http://www.w3.org/2000/01/rdf-schema#" >
]>
<rdf:RDF xmlns="http://example.org/kitchen.owl#"
     xml:base="http://example.org/kitchen.owl"
     xmlns:kitchen="http://example.org/kitchen.owl#"
     xmlns:rdfs="http://www.w3.org/2000/01/rdf-schema#"
     xmlns:owl="http://www.w3.org/2002/07/owl#"
     xmlns:xsd="http://www.w3.org/2001/XMLSchema#"
     xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">
    <owl:Ontology rdf:about="http://example.org/kitchen.owl">
        <owl:imports rdf:resource="http://example.org/base.owl"/>
    </owl:Ontology>
    <owl:ObjectProperty rdf:about="#holds"/>
    <owl:ObjectProperty rdf:about="#tightlyHolds">
        <rdfs:subPropertyOf rdf:resource="#holds"/>
    </owl:ObjectProperty>
    <owl:DatatypeProperty rdf:about="#Freshness">
        <rdfs:range rdf:resource="&xsd;float"/>
    </owl:DatatypeProperty>
    <owl:Class rdf:about="#Food"/>
    <owl:Class rdf:about="#Bread">
        <rdfs:subClassOf rdf:resource="#Food"/>
    </owl:Class>
    <owl:Class rdf:about="#Basket">
        <rdfs:subClassOf>
            <owl:Restriction>
                <owl:onProperty rdf:resource="#holds"/>
                <owl:someValuesFrom rdf:resource="#Food"/>
            </owl:Restriction>
        </rdfs:subClassOf>
    </owl:Class>
</rdf:RDF>
)";

}  // namespace

TEST(RdfXml, AnOwlFileLoadsLikeTurtle) {
  Ontology o;
  Prefixes px;
  o.load(kOwl, px, "kitchen.owl", "file:///tmp/kitchen.owl");
  EXPECT_EQ(px.expand("kitchen:Bread"), "http://example.org/kitchen.owl#Bread");  // its prefix is known now
  EXPECT_TRUE(o.is_subclass("kitchen:Bread", "kitchen:Food"));
  EXPECT_TRUE(o.is_subproperty("kitchen:tightlyHolds", "kitchen:holds"));
  EXPECT_EQ(o.data_range("kitchen:Freshness"), "float");
  EXPECT_TRUE(o.may_relate("kitchen:Basket", "kitchen:holds", "kitchen:Bread"));
  EXPECT_EQ(o.missing_imports(), std::vector<std::string>{"http://example.org/base.owl"});
}

TEST(RdfXml, TextIsToldApartFromTurtle) {
  EXPECT_TRUE(looks_like_rdf_xml(kOwl));
  EXPECT_TRUE(looks_like_rdf_xml("\n  <rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\"/>"));
  EXPECT_FALSE(looks_like_rdf_xml("<http://a> <http://b> <http://c> ."));  // Turtle may start with '<'
  EXPECT_FALSE(looks_like_rdf_xml("@prefix x: <http://x#> ."));
}

TEST(RdfXml, MalformedXmlIsAnErrorNamingTheFileAndLine) {
  Ontology o;
  Prefixes px;
  const std::string broken = std::string(kOwl).replace(std::string(kOwl).find("</owl:Ontology>"), 15, "");
  try {
    o.load(broken, px, "kitchen.owl", "file:///tmp/kitchen.owl");
    FAIL() << "no error";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("kitchen.owl: line "), std::string::npos) << e.what();
  }
}

TEST(RdfXml, ExternalEntitiesAreNotRead) {
  // An ontology from elsewhere must not make the server read its files.
  const auto secret = std::filesystem::temp_directory_path() / "skillbus-rdfxml-secret.txt";
  std::ofstream(secret) << "TOP-SECRET";
  const std::string xxe = std::string(R"(<?xml version="1.0"?>
<!DOCTYPE rdf:RDF [ <!ENTITY leak SYSTEM "file://)") + secret.string() + R"("> ]>
<rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"
         xmlns:rdfs="http://www.w3.org/2000/01/rdf-schema#">
  <rdf:Description rdf:about="http://example.org/x"><rdfs:label>&leak;</rdfs:label></rdf:Description>
</rdf:RDF>)";
  Prefixes px;
  std::vector<Triple> triples;
  try {
    triples = parse_rdf_xml(xxe, px, "xxe.owl", "file:///tmp/xxe.owl");
  } catch (const WmError&) {
    // refusing the document is as good as not expanding the entity
  }
  for (const auto& t : triples) EXPECT_EQ(t.o.value.find("TOP-SECRET"), std::string::npos);
  std::remove(secret.c_str());
}

TEST(OntologyFiles, AFolderLoadsEveryOntologyFileInItAndImportsAreResolvedAmongThem) {
  const auto dir = std::filesystem::temp_directory_path() / "skillbus-onto-folder";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "deeper");
  std::ofstream(dir / "kitchen.owl") << kOwl;
  std::ofstream(dir / "deeper" / "base.ttl") << "@prefix owl: <http://www.w3.org/2002/07/owl#> .\n"
                                                "<http://example.org/base.owl> a owl:Ontology .\n";
  std::ofstream(dir / "notes.txt") << "not an ontology";
  Ontology o;
  Prefixes px;
  const OntologyLoad r = load_ontology_files(o, px, {dir.string()});
  EXPECT_EQ(r.files.size(), 2u);
  EXPECT_TRUE(r.missing_imports.empty());
  EXPECT_TRUE(o.is_subclass("kitchen:Bread", "kitchen:Food"));
  EXPECT_THROW(load_ontology_files(o, px, {(dir / "missing.owl").string()}), WmError);
  std::filesystem::remove_all(dir);
}

TEST(OntologyFiles, BlankNodesOfTwoFilesStayApartWhenTheirTriplesAreWrittenTogether) {
  // Each file's reader names its blank nodes from b1 on: the files' triples, written as one
  // Turtle document (the ontology RPC every process reads, the journal's imports, the
  // SPARQL graph), must not make one restriction of two.
  const auto dir = std::filesystem::temp_directory_path() / "skillbus-onto-blanks";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string head = "@prefix owl: <http://www.w3.org/2002/07/owl#> .\n"
                           "@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .\n"
                           "@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .\n"
                           "@prefix kit: <http://example.org/kit#> .\n";
  std::ofstream(dir / "a.ttl") << head << "kit:A a owl:Class ; rdfs:subClassOf skiros:Location, "
                                          "[ a owl:Restriction ; owl:onProperty skiros:contain ; owl:someValuesFrom kit:X ] .\n"
                                          "kit:X a owl:Class ; rdfs:subClassOf skiros:Product .\n";
  std::ofstream(dir / "b.ttl") << head << "kit:B a owl:Class ; rdfs:subClassOf skiros:Device, "
                                          "[ a owl:Restriction ; owl:onProperty skiros:hasA ; owl:someValuesFrom kit:Y ] .\n"
                                          "kit:Y a owl:Class ; rdfs:subClassOf skiros:Device .\n";
  Ontology live = test::ontology();
  Prefixes px;
  const OntologyLoad r = load_ontology_files(live, px, {dir.string()});
  ASSERT_EQ(r.files.size(), 2u);
  ASSERT_TRUE(live.may_relate("kit:A", "skiros:contain", "kit:X"));
  ASSERT_TRUE(live.may_relate("kit:B", "skiros:hasA", "kit:Y"));
  Ontology again = test::ontology();
  Prefixes px2;
  again.add_triples(parse_turtle(write_turtle(r.triples, px), px2, "written"), px2);
  EXPECT_TRUE(again.may_relate("kit:A", "skiros:contain", "kit:X"));
  EXPECT_TRUE(again.may_relate("kit:B", "skiros:hasA", "kit:Y"));
  EXPECT_FALSE(again.may_relate("kit:A", "skiros:hasA", "kit:Y"));
  EXPECT_FALSE(again.may_relate("kit:B", "skiros:contain", "kit:X"));
  std::filesystem::remove_all(dir);
}

TEST(Containment, AnElementHasOneContainerAndNoCycle) {
  WorldStore s(test::ontology());
  s.apply({Op{Op::AddElement, Element{"skiros:Table-1", "skiros:Table", "t", {}}, {}},
           Op{Op::AddElement, Element{"skiros:Bin-2", "skiros:Bin", "b", {}}, {}},
           Op{Op::AddElement, Element{"skiros:Cube-3", "skiros:Cube", "c", {}}, {}},
           Op{Op::AddRelation, {}, Relation{"skiros:Table-1", "skiros:contain", "skiros:Cube-3"}}});
  const int64_t v = s.version();
  try {  // a second container without leaving the first
    s.apply({Op{Op::AddRelation, {}, Relation{"skiros:Bin-2", "skiros:contain", "skiros:Cube-3"}}});
    FAIL() << "accepted";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("two containers"), std::string::npos) << e.what();
  }
  EXPECT_EQ(s.version(), v);
  EXPECT_EQ(s.relations("", "skiros:contain", "skiros:Cube-3").size(), 1u);  // undone
  // moving it is one transaction: out of the old, into the new
  s.apply({Op{Op::RemoveRelation, {}, Relation{"skiros:Table-1", "skiros:contain", "skiros:Cube-3"}},
           Op{Op::AddRelation, {}, Relation{"skiros:Bin-2", "skiros:contain", "skiros:Cube-3"}}});
  s.apply({Op{Op::AddRelation, {}, Relation{"skiros:Table-1", "skiros:contain", "skiros:Bin-2"}}});
  try {  // Cube-3 in Bin-2 in Table-1 in Cube-3
    s.apply({Op{Op::AddRelation, {}, Relation{"skiros:Cube-3", "skiros:contain", "skiros:Table-1"}}});
    FAIL() << "accepted";
  } catch (const WmError& e) {
    EXPECT_NE(std::string(e.what()).find("containment cycle: "), std::string::npos) << e.what();
  }
}

TEST(Scene, EveryUnknownTypeIsNamedAtOnce) {
  Ontology o = test::ontology();
  Prefixes px;
  const Scene scene = read_scene(R"(@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
@prefix owl: <http://www.w3.org/2002/07/owl#> .
skiros:Bread-1 a skiros:Bread, owl:NamedIndividual .
skiros:Bread-2 a skiros:Bread, owl:NamedIndividual .
skiros:Bread-3 a skiros:Bread, owl:NamedIndividual .
skiros:Soda-4 a skiros:Soda, owl:NamedIndividual .
skiros:Cube-5 a skiros:Cube, owl:NamedIndividual .
)",
                                 o, px, "pantry.ttl");
  try {
    check_scene_types(scene, o, "pantry.ttl");
    FAIL() << "accepted";
  } catch (const WmError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("2 type(s)"), std::string::npos) << what;
    EXPECT_NE(what.find("skiros:Bread (skiros:Bread-1 and 2 more)"), std::string::npos) << what;
    EXPECT_NE(what.find("skiros:Soda (skiros:Soda-4)"), std::string::npos) << what;
  }
}
