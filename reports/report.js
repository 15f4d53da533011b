// Click a header to sort by it (again: the other way). Numbers (data-v) sort by value and before
// text; a missing value (data-v="") sorts last. No library, nothing fetched.
document.querySelectorAll('table.sortable th').forEach(function (th) {
  th.addEventListener('click', function () {
    var body = th.closest('table').tBodies[0], rows = Array.prototype.slice.call(body.rows);
    var dir = th.getAttribute('data-dir') === 'asc' ? -1 : 1;
    th.setAttribute('data-dir', dir > 0 ? 'asc' : 'desc');
    function key(r) {
      var c = r.cells[th.cellIndex], v = c.getAttribute('data-v');
      if (v === '') return [2, 0];
      if (v === null) v = c.textContent;
      var n = Number(v);
      return isNaN(n) || v === '' ? [1, v] : [0, n];
    }
    rows.sort(function (a, b) {
      var x = key(a), y = key(b);
      if (x[0] !== y[0]) return x[0] - y[0];
      return (x[1] < y[1] ? -1 : x[1] > y[1] ? 1 : 0) * dir;
    });
    rows.forEach(function (r) { body.appendChild(r); });
  });
});

// Self-check for readers and for the browser test: counts figures drawn with a non-zero size and,
// with every <details> open, whether anything is wider than the window (then closes them again).
// A link into folded content (a run's row, an engine's audit) opens the folds around its target; the address
// ending in #unfold opens every fold (what the browser test photographs the figures with).
function reveal() {
  var id = decodeURIComponent(location.hash.slice(1));
  if (id === 'unfold') { document.querySelectorAll('details').forEach(function (d) { d.open = true; }); return; }
  var t = id && document.getElementById(id);
  for (var d = t; d; d = d.parentElement) { if (d.tagName === 'DETAILS') d.open = true; }
  if (t) t.scrollIntoView();
}
window.addEventListener('hashchange', reveal);

// Self-check for readers and for the browser test, with every <details> open: counts the figures drawn with a
// non-zero size and whether anything is wider than the window; then closes them again and records the page's
// height (data-height) and where each figure and section starts (data-at), folded unless the address opens folds.
window.addEventListener('load', function () {
  var closed = Array.prototype.filter.call(document.querySelectorAll('details'), function (d) { return !d.open; });
  closed.forEach(function (d) { d.open = true; });
  var figs = document.querySelectorAll('figure.plot svg'), drawn = 0;
  figs.forEach(function (s) { var r = s.getBoundingClientRect(); if (r.width > 0 && r.height > 0) drawn++; });
  document.body.setAttribute('data-figures', drawn + '/' + figs.length);
  var wide = [];
  document.querySelectorAll('body *').forEach(function (el) {
    if (el.closest('pre')) return;
    var r = el.getBoundingClientRect();
    if (r.right > document.documentElement.clientWidth + 1) wide.push(el.tagName.toLowerCase() + (el.id ? '#' + el.id : ''));
  });
  var page = document.documentElement.scrollWidth <= window.innerWidth;
  document.body.setAttribute('data-overflow', page && !wide.length ? 'none' : wide.slice(0, 5).join(' ') || 'page');
  closed.forEach(function (d) { d.open = false; });
  reveal();  // (an address with a target or #unfold: the heights and places below are of that view)
  var at = {};  // where each figure and section starts, for screenshots of one of them
  document.querySelectorAll('figure[id], h2[id]').forEach(function (el) {
    at[el.id] = Math.round(el.getBoundingClientRect().top + window.scrollY);
  });
  document.body.setAttribute('data-at', JSON.stringify(at));
  document.body.setAttribute('data-height', document.documentElement.scrollHeight);
});
