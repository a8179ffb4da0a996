/**
 * The drop-down menus (<details class="menu">: Export, Lanes, Keys): an open one closes on Escape
 * (the focus goes back to its button) and on a press anywhere outside it. The press still reaches
 * what was pressed (the ruler, a lane), and the Keys list, which holds nothing to press, lets
 * presses through to what lies under it (css: .keys-list).
 */

/** Close open menus on Escape and on outside presses; returns the function that stops it. */
export function closeMenusOutside() {
  const openMenus = () => /** @type {HTMLDetailsElement[]} */ (Array.from(document.querySelectorAll("details.menu[open]")));
  const onDown = (/** @type {PointerEvent} */ e) => {
    for (const menu of openMenus()) if (!menu.contains(/** @type {Node} */ (e.target))) menu.open = false;
  };
  const onKey = (/** @type {KeyboardEvent} */ e) => {
    const open = openMenus();
    if (e.key !== "Escape" || !open.length) return;
    for (const menu of open) {
      const hadFocus = menu.contains(document.activeElement);
      menu.open = false;
      const summary = menu.querySelector("summary");
      if (hadFocus && summary) summary.focus();
    }
    // Escape closed a menu and does nothing else here (the selection stays); STOP, registered
    // on the document before this, has already run.
    e.stopPropagation();
  };
  document.addEventListener("pointerdown", onDown, true);
  document.addEventListener("keydown", onKey, true);
  return () => {
    document.removeEventListener("pointerdown", onDown, true);
    document.removeEventListener("keydown", onKey, true);
  };
}
