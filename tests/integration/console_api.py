"""Asks the console's HTTP API (inside the test's network namespace): each request of a
JSON list on argv[2] in turn, [METHOD, PATH, BODY or null, (TOKEN)]; prints a JSON list
of [status, reply] (a reply that is not JSON: its text)."""

import json
import sys
import urllib.error
import urllib.parse
import urllib.request


def ask(url: str, method: str, path: str, body, token: str | None = None) -> list:
    """`url` as `skillbus console` printed it (its token, if any, goes in the header;
    `token` overrides it, "" sends none)."""
    parts = urllib.parse.urlsplit(url)
    given = urllib.parse.parse_qs(parts.query).get("token", [""])[0] if token is None else token
    data = json.dumps(body).encode() if body is not None else None
    headers = {"Content-Type": "application/json"} if data else {}
    if given:
        headers["X-Skillbus-Token"] = given
    req = urllib.request.Request(f"{parts.scheme}://{parts.netloc}{path}", data=data, method=method, headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            status, text = r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        status, text = e.code, e.read().decode()
    try:
        return [status, json.loads(text)]
    except json.JSONDecodeError:
        return [status, text]


if __name__ == "__main__":
    print(json.dumps([ask(sys.argv[1], *r) for r in json.loads(sys.argv[2])]))
