"""The methods beside the paper's family, and what runs and judges every method.

Each method is an object in its own module, registered once (:mod:`inversion.options`): the optimal-control feedforward
(:mod:`.ocp`), the re-planned output (:mod:`.replan`), stable inversion (:mod:`.stable`), the polynomial redefinition
(:mod:`.polynomial`), ZV and ZVD input shaping (:mod:`.shaping`); the automatic choice across them and the family
(:mod:`.automatic`). :mod:`.judged` runs a method on a problem and judges it; :mod:`.bounded_limit` is the least error
any causal feedforward within the bounds reaches, :mod:`.margin` the share of the bound a table keeps and the plant
errors it tolerates. Called ``inversion.baselines`` until issue 55 (the old names still import, with a warning).
"""
