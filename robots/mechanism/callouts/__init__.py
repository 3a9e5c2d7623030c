"""Drawing callouts on joint seats: exact zones, the error model that carries them, the study-file table."""
