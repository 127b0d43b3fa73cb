"""The chain programmes: a held plant's programme built period by period (:mod:`.programme`) and solved by HPIPM's
Riccati interior point (:mod:`.hpipm`), in time linear in the periods. The bounded causal limit
(:mod:`inversion.baselines.bounded_limit`) and the optimal-control table (:mod:`inversion.baselines.ocp`) are its
clients (docs/method.md section 5i)."""
