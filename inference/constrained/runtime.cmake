# The runtime of structurally constrained prediction: the distribution projector (SLSQP per
# component on a predicted TrajectoryDistribution) and the metrics (ADE, FDE, AL, ANLL).
target_sources(foresight_constrained PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/distribution_projector.cc
                                             ${CMAKE_CURRENT_SOURCE_DIR}/prediction_metrics.cc)
target_link_libraries(foresight_constrained PUBLIC foresight_inference)
