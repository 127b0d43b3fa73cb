/* sflm's additions to furo (issue 58): a display equation wider than its column is scaled down to fit it, to no less
   than 70 % of its size -- on a phone's 390 px, 13 of the method's equations were cut -- and one still wider scrolls in
   its own box (sflm.css). Run once MathJax has typeset the page, and again when the window changes width. */
(function () {
  "use strict";
  var LEAST = 0.7;

  function fit() {
    document.querySelectorAll('mjx-container[display="true"]').forEach(function (box) {
      if (box.dataset.sflmSize === undefined) {
        box.dataset.sflmSize = box.style.fontSize;
      }
      box.style.fontSize = box.dataset.sflmSize;
      var math = box.firstElementChild;
      if (!math) {
        return;
      }
      var need = math.getBoundingClientRect().width;
      var room = box.clientWidth;
      if (need > room && room > 0) {
        var size = parseFloat(window.getComputedStyle(box).fontSize);
        box.style.fontSize = size * Math.max(LEAST, (0.99 * room) / need) + "px";
      }
    });
  }

  window.addEventListener("load", function () {
    var typeset = window.MathJax && window.MathJax.startup && window.MathJax.startup.promise;
    (typeset || Promise.resolve()).then(fit);
  });
  window.addEventListener("resize", fit);
})();
