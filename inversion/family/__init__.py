"""The paper's method: the family of redefinitions by sums of stable exponentials (:mod:`.ssef`), a
member's anchors, closed form, settle tail, figures and checks, the evaluation of a member, the
automatic choice, the exploration of the family and the method's runner (:mod:`.piecewise`)."""
