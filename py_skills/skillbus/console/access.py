"""Who may use the console: the holder of its token.

The console commands the robot (it holds the bus key), over HTTP on a TCP port that
every user and every web page in a browser on the machine can reach. So each run makes
a token and prints the URL with it (``http://127.0.0.1:8080/?token=...``, as Jupyter
does). Opening that URL sets a cookie (HttpOnly, SameSite=Strict: a page of another
site that posts to the console does not carry it) and drops the token from the address;
every API request and the live WebSocket must then carry the cookie, the
``X-Skillbus-Token`` header, or ``?token=``. The page and its static files need none:
they hold nothing. ``$SKILLBUS_CONSOLE_TOKEN`` (or ``--token``, which every user sees in
the process list) sets the token (a script's); ``--no-token`` turns the check off (a
console behind a proxy that authenticates).
"""

from __future__ import annotations

import hmac
import secrets

COOKIE = "skillbus_console"  # the name's stem: each console's cookie is named after its token (cookie_name)
TOKEN_ENV = "SKILLBUS_CONSOLE_TOKEN"  # a token of one's own, kept out of the process list
HEADER = "x-skillbus-token"


def new_token() -> str:
    return secrets.token_urlsafe(24)


def cookie_name(token: str | None) -> str:
    """The cookie of the console with `token`. Cookies belong to a host, not to a port: two
    consoles on one machine (``--port 8090``) each set theirs without overwriting the
    other's (one name for all made the first console's page answer 401 once the second's
    was opened). A digest of the token, not the token.

    >>> cookie_name("abc"), cookie_name(None)
    ('skillbus_console_ba7816bf', 'skillbus_console')
    """
    if token is None:
        return COOKIE
    import hashlib
    return f"{COOKIE}_{hashlib.sha256(token.encode()).hexdigest()[:8]}"


def presented(headers, query: dict[str, str], cookies: dict[str, str], token: str | None = None) -> str:
    return query.get("token") or headers.get(HEADER, "") or cookies.get(cookie_name(token), "")


def allowed(token: str | None, given: str) -> bool:
    """No token: everyone; else the same token (compared in constant time).

    >>> allowed(None, ""), allowed("abc", "abc"), allowed("abc", "abd"), allowed("abc", "")
    (True, True, False, False)
    """
    return token is None or (bool(given) and hmac.compare_digest(token.encode(), given.encode()))


NEEDS_TOKEN = "this console needs its token: open the URL `skillbus console` printed (with ?token=...)"
