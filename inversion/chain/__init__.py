"""The chain programmes: a held plant's programme built period by period (:mod:`.programme`) and solved by HPIPM's
Riccati interior point (:mod:`.hpipm`), in time linear in the periods. The bounded causal limit
(:mod:`inversion.methods.bounded_limit`) and the optimal-control table (:mod:`inversion.methods.ocp`) are its
clients (docs/method.md section 5i)."""
