// sim/ holds the Simbody plant; see simbody_model.h.
