// The clicked cell's own link, in the line above the map.
// A module of the page's script (bundled by src/render/page/bundle.rs), used
// only when the config names a link field: a click on a cell (Enter, a second
// tap) writes its link in the line above the map, a real <a> the reader
// follows (in a new tab when the config says so). Only http:, https: and
// relative URLs become links, checked here again on the text the data
// carries; any other value (javascript:, data:, ...) is shown as text and
// never followed. Text reaches the page through textContent and attribute
// values only.
import { data, labels, part } from "./model.js";

var linkLine = part("link");
var FOLLOW = /^(https?:\/\/|[^:\/?#]*([\/?#]|$))/i;
function followable(href) {
  return typeof href === "string" && href.length > 0 && !/[\u0000-\u0020\u007f-\u009f\\]/.test(href) && FOLLOW.test(href);
}
export function showLink(i) {
  if (!linkLine) { return; }
  while (linkLine.firstChild) { linkLine.removeChild(linkLine.firstChild); }
  var l = data.nodes[i].link;
  if (!l) { linkLine.hidden = true; return; }
  var name = document.createElement("span");
  name.className = "np-link-name";
  name.textContent = labels[i] + " \u2014 " + (data.linkName || "link") + ": ";
  linkLine.appendChild(name);
  if (l.ok && followable(l.href)) {
    var a = document.createElement("a");
    a.className = "np-link-open";
    a.setAttribute("href", l.href);
    if (data.newTab) {
      a.setAttribute("target", "_blank");
      a.textContent = l.href + " \u2197";
      a.setAttribute("aria-label", l.href + " (opens in a new tab)");
    } else {
      a.textContent = l.href;
    }
    a.setAttribute("rel", "noopener noreferrer");
    linkLine.appendChild(a);
  } else {
    var t = document.createElement("span");
    t.className = "np-link-refused";
    t.textContent = l.href + " (not a web link: not followed)";
    linkLine.appendChild(t);
  }
  linkLine.hidden = false;
}
