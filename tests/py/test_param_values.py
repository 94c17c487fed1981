"""Text values of skill parameters parse strictly by type (skillbus run -p KEY=VALUE)."""

import pytest

from skillbus.skill.values import parse_text
from skillbus.world.element import Element


@pytest.mark.parametrize("data_type,text,value", [
    ("bool", "true", True), ("bool", "TRUE", True), ("bool", "1", True), ("bool", "False", False),
    ("bool", "0", False), ("int", "5", 5), ("int", "-3", -3), ("float", "0.5", 0.5), ("float", "2", 2.0),
    ("str", "", ""), ("list", "[1, 2]", [1, 2]), ("dict", '{"a": 1}', {"a": 1}),
])
def test_values_of_their_type_parse(data_type, text, value):
    assert parse_text(data_type, "", text) == value


@pytest.mark.parametrize("data_type,text", [
    ("bool", "maybe"), ("bool", "yes"), ("bool", ""), ("int", "5.5"), ("int", "five"), ("float", "0.5x"),
    ("list", '{"a": 1}'), ("dict", "[1]"), ("list", "[1,"), ("element", ""), ("tensor", "1"),
])
def test_anything_else_is_an_error(data_type, text):
    with pytest.raises(ValueError):
        parse_text(data_type, "", text)


def test_an_element_is_an_id_of_the_parameters_concept():
    e = parse_text("element", "skiros:Product", "skiros:Cube-2")
    assert isinstance(e, Element) and (e.id, e.type) == ("skiros:Cube-2", "skiros:Product")
