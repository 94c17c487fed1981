"""Drives the skillbus console in headless Chromium (Debian's, through Playwright), inside
the test's network namespace, as a user would: one scenario per run, what it saw as one
JSON line on stdout, screenshots into --shots.

    console_browser.py URL SCENARIO --shots DIR [--task N] [--element ID]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from playwright.sync_api import Page, sync_playwright

CHROMIUM = "/usr/bin/chromium"
TIMEOUT_MS = 30_000


def root_state(page: Page) -> str | None:
    return page.get_attribute('[data-testid=task-tree] .node[data-node="0"]', "data-state", timeout=TIMEOUT_MS)


def shown_tick(page: Page) -> int:
    return int(page.get_attribute("[data-testid=task-state]", "data-tick", timeout=TIMEOUT_MS))


def tree_rows(page: Page) -> list[dict]:
    return page.eval_on_selector_all("[data-testid=task-tree] .node", """rows => rows.map(r => ({
        id: Number(r.dataset.node), state: r.dataset.state,
        message: (r.querySelector('.msg') || {textContent: ''}).textContent}))""")


def wait_until(what: str, check, timeout: float, interval: float = 0.05):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = check()
        if value:
            return value
        time.sleep(interval)
    raise TimeoutError(f"{what} within {timeout} s")


def open_console(browser, url: str) -> Page:
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.set_default_timeout(TIMEOUT_MS)
    page.goto(url)
    page.wait_for_selector("#connection.good")
    return page


def start_clear_table(page: Page, shots: Path, args) -> dict:
    page.click("[data-testid=tab-skills]")
    page.click('[data-testid=skill-list] .item[data-skill="ClearTable"]')
    page.wait_for_selector("[data-testid=start]")
    page.screenshot(path=str(shots / "console-skills.png"))
    page.click("[data-testid=start]")
    page.wait_for_selector('[data-testid=task-tree] .node[data-node="0"]')
    states: list[str] = []
    shot_taken = False

    def ended() -> bool:
        nonlocal shot_taken
        s = root_state(page)
        if not states or states[-1] != s:
            states.append(s)
        if s == "Running" and not shot_taken and len(tree_rows(page)) > 3:
            page.screenshot(path=str(shots / "console-task-running.png"))
            shot_taken = True
        return s in ("Success", "Failure")

    wait_until("ClearTable's end", ended, 600)
    page.screenshot(path=str(shots / "console-task-done.png"), full_page=True)
    task = int(page.get_attribute("[data-testid=task-list] .item.selected", "data-task"))
    out = {"task": task, "states": states, "rows": tree_rows(page), "message": page.inner_text("[data-testid=message]")}
    # the live 3D view of the scene the task left
    page.click("[data-testid=tab-3d]")
    page.wait_for_function("document.querySelector('[data-testid=live-contacts]').textContent.startsWith('frame')")
    page.wait_for_timeout(500)
    page.screenshot(path=str(shots / "console-3d.png"))
    out["live3d"] = page.inner_text("[data-testid=live-contacts]")
    out["canvas"] = page.locator("[data-testid=live-3d] canvas").count()
    return out


def control_cli_task(page: Page, shots: Path, args) -> dict:
    """Resume, pause, step, resume and stop a task someone else starts (args.task) and
    holds paused once this page is open (it says READY)."""
    page.click("[data-testid=tab-tasks]")
    print("READY", flush=True)
    page.click(f'[data-testid=task-list] .item[data-task="{args.task}"]', timeout=60_000)
    # (Idle when the hold came before its first tick: a queued task paused begins paused)
    wait_until("the task's tree", lambda: root_state(page) in ("Idle", "Running"), 30)
    out: dict = {}
    # The test holds the task with `skillbus pause` as soon as it starts (under lockstep a
    # ClearTable can be over before a browser on a busy machine has clicked): resumed
    # from here first, it must tick on.
    time.sleep(1.0)
    out["held"] = shown_tick(page)
    page.click("[data-testid=task-resume]")
    wait_until("ticks after resuming the held task", lambda: shown_tick(page) > out["held"] + 3, 20)
    out["after_first_resume"] = shown_tick(page)
    page.click("[data-testid=task-pause]")

    def settled() -> bool:  # (a tick under way when the pause came is still shown, when it arrives)
        before = shown_tick(page)
        time.sleep(1.0)
        return shown_tick(page) == before

    wait_until("the shown tick to settle after the pause", settled, 30)
    out["paused_at"] = shown_tick(page)
    time.sleep(1.5)
    out["after_pause"] = shown_tick(page)
    page.screenshot(path=str(shots / "console-task-paused.png"))
    page.click("[data-testid=task-step]")
    wait_until("the step's tick", lambda: shown_tick(page) > out["after_pause"], 10)
    time.sleep(1.0)
    out["after_step"] = shown_tick(page)
    page.click("[data-testid=task-resume]")
    wait_until("ticks after the resume", lambda: shown_tick(page) > out["after_step"] + 3, 20)
    out["after_resume"] = shown_tick(page)
    page.click("[data-testid=task-stop]")
    wait_until("the stopped task's end", lambda: root_state(page) in ("Success", "Failure"), 30)
    out["final"] = root_state(page)
    out["root_message"] = tree_rows(page)[0]["message"]
    return out


def rename(page: Page, label: str) -> str:
    """Saves a new label for the element the page shows; the page's answer."""
    page.wait_for_selector("[data-testid=label-input]")
    page.fill("[data-testid=label-input]", label)
    page.click("[data-testid=save-label]")
    wait_until(f"the answer to the rename to {label!r}", lambda: "done" in page.inner_text("[data-testid=message]"), 10)
    return page.inner_text("[data-testid=message]")


def edit_element(page: Page, shots: Path, args) -> dict:
    """Renames args.element from the element page; then a second page edits the element
    the first one shows, and the first page's edit of its stale read is refused."""
    out: dict = {}
    page.click("[data-testid=tab-world]")
    page.fill("[data-testid=search-label]", "")
    page.fill("[data-testid=search-type]", "skiros:Product")
    page.click("[data-testid=world-search] button")
    page.click(f'[data-testid=search-results] .item[data-element="{args.element}"]')
    out["renamed"] = rename(page, "renamed in the console")
    page.wait_for_function("document.querySelector('[data-testid=label-input]').value === 'renamed in the console'")
    page.screenshot(path=str(shots / "console-world.png"))

    other = open_console(page.context.browser, args.url)  # (a browser of its own: the URL with the token)
    other.click("[data-testid=tab-world]")
    other.click(f'[data-testid=world-tree] .item[data-element="{args.element}"]')
    rename(other, "renamed by someone else")

    page.fill("[data-testid=label-input]", "my stale rename")
    page.click("[data-testid=save-label]")
    wait_until("the refusal", lambda: page.get_attribute("[data-testid=message]", "class") == "error", 10)
    out["stale"] = page.inner_text("[data-testid=message]")
    page.screenshot(path=str(shots / "console-world-stale.png"))
    return out


def replay_log(page: Page, shots: Path, args) -> dict:
    """Opens args.log on the Replay page and scrubs the timeline forward until the world
    model shows a cube in the gripper."""
    page.click("[data-testid=tab-replay]")
    page.fill("[data-testid=replay-path]", args.log)
    page.click("[data-testid=replay-open] button")
    page.wait_for_selector("[data-testid=replay-digest]", timeout=60_000)
    timeline = page.locator("[data-testid=timeline]")
    first, last = int(timeline.get_attribute("min")), int(timeline.get_attribute("max"))
    held = '[data-testid=replay-world] .item[data-element^="skiros:Cube"][data-parent^="skiros:Gripper"]'
    for frame in range(first, last + 1, max(1, (last - first) // 60)):
        timeline.fill(str(frame))
        # (data-asked: a frame the logger dropped is answered with the nearest before it)
        page.wait_for_selector(f'[data-testid=replay-frame-number][data-asked="{frame}"]')
        if page.locator(held).count():
            break
    else:
        raise AssertionError(f"no frame of {first}..{last} shows a cube in the gripper")
    page.wait_for_timeout(300)  # (the 3D view draws the frame)
    page.screenshot(path=str(shots / "console-replay.png"))
    return {"frame": frame, "first": first, "last": last, "cube": page.get_attribute(held, "data-element"),
            "contacts": page.inner_text("[data-testid=replay-contacts]"),
            "digest": page.inner_text("[data-testid=replay-digest]"),
            "tasks": page.inner_text("[data-testid=replay-tasks]")[:2000]}


SCENARIOS = {"start_clear_table": start_clear_table, "control_cli_task": control_cli_task,
             "edit_element": edit_element, "replay_log": replay_log}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("scenario", choices=sorted(SCENARIOS))
    ap.add_argument("--shots", required=True)
    ap.add_argument("--task", type=int, default=0)
    ap.add_argument("--element", default="")
    ap.add_argument("--log", default="")
    args = ap.parse_args()
    shots = Path(args.shots)
    shots.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        # (no sandbox: the test's network namespace is a user namespace, where Chromium's
        # own sandbox cannot be set up)
        # (software WebGL for the 3D view: there is no GPU)
        browser = p.chromium.launch(executable_path=CHROMIUM,
                                    args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
        page = open_console(browser, args.url)
        try:
            out = SCENARIOS[args.scenario](page, shots, args)
        except Exception:
            page.screenshot(path=str(shots / f"failed-{args.scenario}.png"), full_page=True)
            raise
        print(json.dumps(out), flush=True)
        browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
