"""A manipulation skill's configuration: its class defaults, then a YAML file (or inline
YAML text) given by the skill's ``Config`` parameter, then the skill's own parameters,
each overriding the one before. A task file for ``ManipTask`` (``skillbus run ManipTask
-p Task=...``) and ``skillbus generate`` lists skills the same way::

    skills:
      - name: open          # a registered key (skillbus.manip.registry)
        Object: cabinet/drawer_joint
        distance: 0.15
      - name: pick
        Object: red

>>> merge({"a": 1, "b": 2}, "b: 3", {"c": 4})
{'a': 1, 'b': 3, 'c': 4}
>>> merge({}, "- 1", {})
Traceback (most recent call last):
...
skillbus.manip.config.ConfigError: the configuration must be a mapping (key: value), not a list
"""

from __future__ import annotations

import os

import yaml


class ConfigError(ValueError):
    pass


def load(text_or_path: str) -> dict:
    """A mapping from YAML text or from the YAML file it names ("" gives {})."""
    if not text_or_path or not text_or_path.strip():
        return {}
    text = text_or_path
    looks_like_path = "\n" not in text and not text.lstrip().startswith("{") and text.strip().endswith((".yaml", ".yml"))
    if looks_like_path:
        if not os.path.isfile(text):
            raise ConfigError(f"configuration file {text} does not exist")
        with open(text, encoding="utf-8") as f:
            text = f.read()
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise ConfigError(f"the configuration is not valid YAML: {e}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"the configuration must be a mapping (key: value), not a {type(data).__name__}")
    return data


def merge(defaults: dict, text_or_path: str, params: dict) -> dict:
    out = dict(defaults)
    out.update(load(text_or_path))
    out.update(params)
    return out


def load_task(path: str) -> list[dict]:
    """The ``skills:`` list of a task file (or of YAML text: ``skillbus generate`` hands a
    task over as compact JSON, so that nothing of an episode's folder enters its
    messages): each a mapping with a ``name``. ConfigError names the entry that is
    wrong."""
    data = load(path)
    skills = data.get("skills")
    if not isinstance(skills, list) or not skills:
        raise ConfigError(f"{path}: 'skills' must be a non-empty list")
    for i, s in enumerate(skills):
        if not isinstance(s, dict) or not isinstance(s.get("name"), str):
            raise ConfigError(f"{path}: skills[{i}] must be a mapping with a 'name'")
    return skills
