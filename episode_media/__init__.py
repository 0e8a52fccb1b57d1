"""Media made from HDF5 episodes: the motion as USD (`b2d export usd`) and the cameras with their
tactile heatmaps as an MP4 or PNG strip (`b2d show`). Reads episodes only through episodes.reader."""
