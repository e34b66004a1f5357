"""Model order reduction of FE gear bodies (layer 5): FE model -> reductor -> reduced body."""
