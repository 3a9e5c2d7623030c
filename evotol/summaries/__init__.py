"""The plain data a user study's report is drawn from: the JSON summary (:mod:`.user_study`), error
maps over the workspace (:mod:`.workspace_map`) and the what-if explorer's data (:mod:`.explorer_data`)."""
