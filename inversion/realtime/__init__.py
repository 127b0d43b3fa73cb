"""What runs beside the link: a result as C99 (:mod:`.feedforward_c`) and as a feedforward FMU (:mod:`.feedforward_fmu`)."""
