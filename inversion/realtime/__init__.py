"""What runs beside the link: a result as C99 (:mod:`.export`) and as a feedforward FMU (:mod:`.fmu`)."""
